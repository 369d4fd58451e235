#include "moslam/weak/losses.h"

#include <cmath>
#include <functional>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"
#include "moslam/weak/cues.h"

namespace moslam::weak {
namespace {

using torch::indexing::Slice;

const auto kDouble = torch::TensorOptions().dtype(torch::kFloat64);

// Random cues in [0, C) with about a quarter of the pixels unknown.
torch::Tensor RandomCues(int64_t n, int64_t c, int64_t h, int64_t w) {
  torch::Tensor cues = torch::randint(0, c, {n, h, w}, torch::kInt64);
  const torch::Tensor unknown = torch::rand({n, h, w}) < 0.25;
  return torch::where(unknown, torch::full_like(cues, kUnknown), cues);
}

// Central differences of a scalar function of `x`, element by element.
torch::Tensor NumericGradient(const std::function<torch::Tensor(const torch::Tensor&)>& f,
                              const torch::Tensor& x, double eps) {
  torch::NoGradGuard no_grad;
  torch::Tensor grad = torch::zeros_like(x);
  torch::Tensor flat = x.clone();
  auto values = flat.view({-1});
  auto out = grad.view({-1});
  for (int64_t i = 0; i < values.numel(); ++i) {
    const double v = values[i].item<double>();
    values[i] = v + eps;
    const double plus = f(flat).item<double>();
    values[i] = v - eps;
    const double minus = f(flat).item<double>();
    values[i] = v;
    out[i] = (plus - minus) / (2.0 * eps);
  }
  return grad;
}

torch::Tensor AnalyticGradient(const std::function<torch::Tensor(const torch::Tensor&)>& f,
                               const torch::Tensor& x) {
  torch::Tensor leaf = x.clone().requires_grad_(true);
  f(leaf).backward();
  return leaf.grad();
}

TEST(Losses, SeedingGradientMatchesFiniteDifferences) {
  torch::manual_seed(1);
  const torch::Tensor logits = torch::randn({2, 3, 4, 5}, kDouble);
  const torch::Tensor cues = RandomCues(2, 3, 4, 5);
  ASSERT_GT((cues == kUnknown).sum().item<int64_t>(), 0);
  const auto f = [&](const torch::Tensor& x) { return SeedingLoss(x, cues); };
  const torch::Tensor analytic = AnalyticGradient(f, logits);
  const torch::Tensor numeric = NumericGradient(f, logits, 1e-6);
  EXPECT_LT((analytic - numeric).abs().max().item<double>(), 1e-8);
  EXPECT_GT(analytic.abs().max().item<double>(), 1e-3);
  // Unknown pixels get no gradient.
  const torch::Tensor unknown = (cues == kUnknown).unsqueeze(1).expand_as(analytic);
  EXPECT_EQ(analytic.masked_select(unknown).abs().max().item<double>(), 0.0);
}

TEST(Losses, ConstrainGradientMatchesFiniteDifferences) {
  torch::manual_seed(2);
  const torch::Tensor logits = torch::randn({2, 3, 4, 5}, kDouble);
  const torch::Tensor q = torch::softmax(2.0 * torch::randn({2, 3, 4, 5}, kDouble), 1);
  const auto f = [&](const torch::Tensor& x) { return ConstrainLoss(x, q); };
  const torch::Tensor analytic = AnalyticGradient(f, logits);
  const torch::Tensor numeric = NumericGradient(f, logits, 1e-6);
  EXPECT_LT((analytic - numeric).abs().max().item<double>(), 1e-8);
  EXPECT_GT(analytic.abs().max().item<double>(), 1e-3);
}

TEST(Losses, SeedingLossIsClassBalanced) {
  torch::manual_seed(3);
  // 100 pixels seeded with class 0, one with class 1.
  const torch::Tensor logits = torch::randn({1, 2, 1, 102}, kDouble);
  torch::Tensor cues = torch::zeros({1, 1, 102}, torch::kInt64);
  cues.index_put_({0, 0, 100}, 1);
  cues.index_put_({0, 0, 101}, kUnknown);
  const torch::Tensor log_p = torch::log_softmax(logits, 1);
  const double class0 = -log_p.index({0, 0, 0, Slice(0, 100)}).mean().item<double>();
  const double class1 = -log_p.index({0, 1, 0, 100}).item<double>();
  const double loss = SeedingLoss(logits, cues).item<double>();
  EXPECT_NEAR(loss, 0.5 * (class0 + class1), 1e-12);
  // Not the plain mean over seeded pixels.
  EXPECT_GT(std::abs(loss - (100.0 * class0 + class1) / 101.0), 1e-3);

  // The lone seed moves the loss as much as all hundred together.
  const torch::Tensor grad =
      AnalyticGradient([&](const torch::Tensor& x) { return SeedingLoss(x, cues); }, logits);
  const torch::Tensor p = torch::softmax(logits, 1);
  EXPECT_NEAR(grad.index({0, 1, 0, 100}).item<double>(),
              -0.5 * (1.0 - p.index({0, 1, 0, 100}).item<double>()), 1e-12);
  EXPECT_NEAR(grad.index({0, 0, 0, Slice(0, 100)}).sum().item<double>(),
              -0.5 * (1.0 - p.index({0, 0, 0, Slice(0, 100)})).mean().item<double>(), 1e-12);
}

TEST(Losses, UnbalancedSeedingLossIsThePlainMeanOverSeeds) {
  torch::manual_seed(4);
  const torch::Tensor logits = torch::randn({2, 3, 2, 5}, kDouble);
  torch::Tensor cues = torch::randint(0, 3, {2, 2, 5}, torch::kInt64);
  cues.index_put_({0, 1, 2}, kUnknown);
  cues.index_put_({1, 0, 4}, kUnknown);
  const torch::Tensor seeded = cues.ne(kUnknown);
  const torch::Tensor log_p = torch::log_softmax(logits, 1).gather(
      1, torch::where(seeded, cues, torch::zeros_like(cues)).unsqueeze(1));
  const double expected = -log_p.squeeze(1).masked_select(seeded).mean().item<double>();
  EXPECT_NEAR(SeedingLoss(logits, cues, /*balance=*/0.0).item<double>(), expected, 1e-12);
  // Its gradient against central differences, as for the balanced form.
  const auto f = [&](const torch::Tensor& x) { return SeedingLoss(x, cues, 0.0); };
  const torch::Tensor analytic = AnalyticGradient(f, logits);
  const torch::Tensor numeric = NumericGradient(f, logits, 1e-6);
  EXPECT_LT((analytic - numeric).abs().max().item<double>(), 1e-8);
}

TEST(Losses, PartlyBalancedSeedingLossWeighsClassesByAPowerOfTheirSeedCount) {
  // 3 seeds of class 0 and 1 of class 1, one pixel unseeded: with balance b a class-0 seed
  // weighs 3^-b and the class-1 seed 1, normalized by 3 * 3^-b + 1.
  torch::manual_seed(5);
  const torch::Tensor logits = torch::randn({1, 2, 1, 5}, kDouble);
  const torch::Tensor cues =
      torch::tensor({0, 0, 0, 1, static_cast<int>(kUnknown)}, torch::kInt64).view({1, 1, 5});
  const torch::Tensor log_p = torch::log_softmax(logits, 1);
  const double nll0 = -log_p.index({0, 0, 0, Slice(0, 3)}).sum().item<double>();
  const double nll1 = -log_p.index({0, 1, 0, 3}).item<double>();
  for (const double b : {0.0, 0.5, 1.0}) {
    const double w0 = std::pow(3.0, -b);
    const double expected = (w0 * nll0 + nll1) / (3.0 * w0 + 1.0);
    EXPECT_NEAR(SeedingLoss(logits, cues, b).item<double>(), expected, 1e-12) << "balance " << b;
  }
  const auto f = [&](const torch::Tensor& x) { return SeedingLoss(x, cues, 0.5); };
  EXPECT_LT(
      (AnalyticGradient(f, logits) - NumericGradient(f, logits, 1e-6)).abs().max().item<double>(),
      1e-8);
  EXPECT_THROW(SeedingLoss(logits, cues, 1.5), InputError);
}

TEST(Losses, SeedingLossWithoutSeedsIsAZeroWithAGraph) {
  const torch::Tensor logits = torch::randn({1, 3, 4, 4}).requires_grad_(true);
  const torch::Tensor cues = torch::full({1, 4, 4}, int64_t{kUnknown}, torch::kInt64);
  const torch::Tensor loss = SeedingLoss(logits, cues);
  EXPECT_EQ(loss.item<float>(), 0.0f);
  ASSERT_TRUE(loss.requires_grad());
  loss.backward();
  ASSERT_TRUE(logits.grad().defined());
  EXPECT_EQ(logits.grad().abs().max().item<float>(), 0.0f);
}

TEST(Losses, BadCuesAreInputErrors) {
  const torch::Tensor logits = torch::randn({1, 3, 4, 4});
  EXPECT_THROW(SeedingLoss(logits, torch::full({1, 4, 4}, 3, torch::kInt64)), InputError);
  EXPECT_THROW(SeedingLoss(logits, torch::zeros({1, 2, 4}, torch::kInt64)), InputError);
  EXPECT_THROW(ConstrainLoss(logits, torch::zeros({1, 3, 4, 3})), InputError);
}

TEST(Losses, ConstrainLossIsZeroOnlyAtTheNetworkOutput) {
  torch::manual_seed(4);
  const torch::Tensor logits = torch::randn({2, 4, 3, 3}, kDouble);
  EXPECT_NEAR(ConstrainLoss(logits, torch::softmax(logits, 1)).item<double>(), 0.0, 1e-14);
  const torch::Tensor other = torch::softmax(logits + torch::randn_like(logits), 1);
  EXPECT_GT(ConstrainLoss(logits, other).item<double>(), 1e-3);
  // Hard targets (zeros in Q) stay finite.
  const torch::Tensor hard =
      torch::one_hot(logits.argmax(1), 4).permute({0, 3, 1, 2}).to(torch::kFloat64);
  EXPECT_TRUE(std::isfinite(ConstrainLoss(logits, hard).item<double>()));
}

// A 2-label problem on an image with a vertical edge: left black, right white; the logits are a
// slow ramp across the edge, so the network output is blurry there.
struct EdgeProblem {
  static constexpr int kH = 16, kW = 32, kEdge = 16;
  torch::Tensor logits;
  cv::Mat image;  // at twice the logits' resolution: CrfTargets resizes it
  EdgeProblem() {
    logits = torch::zeros({1, 2, kH, kW});
    for (int x = 0; x < kW; ++x) {
      logits.index_put_({0, 1, Slice(), x}, 0.12f * (x - (kEdge - 0.5f)));
    }
    image = cv::Mat(2 * kH, 2 * kW, CV_8UC3, cv::Scalar(10, 10, 10));
    image.colRange(2 * kEdge, 2 * kW).setTo(cv::Scalar(240, 240, 240));
  }
  // Mean |P(label 1) - step| over the columns within `band` of the edge.
  static double EdgeError(const torch::Tensor& p, int band) {
    double error = 0.0;
    for (int x = kEdge - band; x < kEdge + band; ++x) {
      const double truth = x >= kEdge ? 1.0 : 0.0;
      error += (p.index({0, 1, Slice(), x}) - truth).abs().mean().item<double>();
    }
    return error / (2 * band);
  }
};

TEST(Losses, CrfTargetsAreProbabilitiesSharpenedAlongEdges) {
  const EdgeProblem problem;
  semantic::DenseCrf crf{semantic::DenseCrfOptions()};
  const torch::Tensor q = CrfTargets(problem.logits, {problem.image}, crf);
  ASSERT_EQ(q.sizes(), problem.logits.sizes());
  EXPECT_LT((q.sum(1) - 1.0f).abs().max().item<float>(), 1e-4f);
  EXPECT_GE(q.min().item<float>(), 0.0f);
  const torch::Tensor p = torch::softmax(problem.logits, 1);
  const double before = EdgeProblem::EdgeError(p, 4);
  const double after = EdgeProblem::EdgeError(q, 4);
  RecordProperty("edge_error_softmax", std::to_string(before));
  RecordProperty("edge_error_crf", std::to_string(after));
  EXPECT_LT(after, 0.5 * before) << "softmax " << before << " CRF " << after;
  // The jump across the edge grows.
  const auto jump = [](const torch::Tensor& t) {
    return (t.index({0, 1, Slice(), EdgeProblem::kEdge}) -
            t.index({0, 1, Slice(), EdgeProblem::kEdge - 1}))
        .mean()
        .item<double>();
  };
  EXPECT_GT(jump(q), 2.0 * jump(p));

  // A batch of two (one grey image) gives each image its own refinement.
  cv::Mat grey;
  cv::cvtColor(problem.image, grey, cv::COLOR_BGR2GRAY);
  const torch::Tensor batch =
      CrfTargets(torch::cat({problem.logits, problem.logits}), {problem.image, grey}, crf);
  ASSERT_EQ(batch.size(0), 2);
  EXPECT_LT((batch[0] - q[0]).abs().max().item<float>(), 1e-5f);
  EXPECT_LT(EdgeProblem::EdgeError(batch.index({Slice(1, 2)}), 4), 0.5 * before);
  EXPECT_THROW(CrfTargets(problem.logits, {}, crf), InputError);
}

// A 1 x rows x cols cue tensor from row-major values.
torch::Tensor CueTensor(int64_t rows, int64_t cols, std::vector<int64_t> values) {
  return torch::tensor(values, torch::kInt64).view({1, rows, cols});
}

TEST(Losses, DownsampleCuesKeepsAgreeingWellSeededCells) {
  // 4 x 4 -> 2 x 2: cells of 2 x 2 pixels.
  const int64_t u = kUnknown;
  const torch::Tensor cues = CueTensor(4, 4,
                                       {1, 1, 2, 2,  //
                                        1, 1, 3, u,  //
                                        u, u, 4, u,  //
                                        u, 5, u, u});
  const torch::Tensor small = DownsampleCues(cues, 2, 2);
  ASSERT_EQ(small.sizes(), (std::vector<int64_t>{1, 2, 2}));
  EXPECT_EQ(small[0][0][0].item<int64_t>(), 1);  // all agree
  EXPECT_EQ(small[0][0][1].item<int64_t>(), u);  // 2 vs 3 disagree
  EXPECT_EQ(small[0][1][0].item<int64_t>(), u);  // a quarter seeded
  EXPECT_EQ(small[0][1][1].item<int64_t>(), u);  // a quarter seeded
  const torch::Tensor half = CueTensor(2, 2, {4, u, 4, u});
  EXPECT_EQ(DownsampleCues(half, 1, 1)[0][0][0].item<int64_t>(), 4);  // exactly half
  // Non-integer ratios partition the input: 5 -> 2 gives cells of 2 and 3 columns.
  const torch::Tensor row = CueTensor(1, 5, {7, 7, u, 8, 8});
  const torch::Tensor r = DownsampleCues(row, 1, 2);
  EXPECT_EQ(r[0][0][0].item<int64_t>(), 7);
  EXPECT_EQ(r[0][0][1].item<int64_t>(), 8);
  EXPECT_THROW(DownsampleCues(row, 1, 6), InputError);
}

TEST(Losses, FewTrainingStepsLowerTheSeedingLoss) {
  torch::manual_seed(5);
  at::set_num_threads(1);
  // Input: left half dark, right half bright, with noise; seeds on both sides.
  torch::Tensor input = torch::full({2, 3, 16, 16}, -0.5f);
  input.index_put_({Slice(), Slice(), Slice(), Slice(8, 16)}, 0.5f);
  input += 0.2f * torch::randn_like(input);
  torch::Tensor cues = torch::full({2, 16, 16}, int64_t{kUnknown}, torch::kInt64);
  cues.index_put_({Slice(), Slice(), Slice(0, 4)}, 0);
  cues.index_put_({Slice(), Slice(), Slice(13, 16)}, 1);
  cues.index_put_({1, Slice(0, 2), Slice(13, 16)}, 2);  // a rare third class

  torch::nn::Sequential net(torch::nn::Conv2d(torch::nn::Conv2dOptions(3, 8, 3).padding(1)),
                            torch::nn::ReLU(),
                            torch::nn::Conv2d(torch::nn::Conv2dOptions(8, 3, 1)));
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(0.02));
  const double initial = SeedingLoss(net->forward(input), cues).item<double>();
  double final_loss = initial;
  for (int step = 0; step < 30; ++step) {
    adam.zero_grad();
    const torch::Tensor loss = SeedingLoss(net->forward(input), cues);
    loss.backward();
    adam.step();
    final_loss = loss.item<double>();
  }
  final_loss = SeedingLoss(net->forward(input), cues).item<double>();
  RecordProperty("seeding_loss_initial", std::to_string(initial));
  RecordProperty("seeding_loss_final", std::to_string(final_loss));
  EXPECT_LT(final_loss, 0.7 * initial) << "initial " << initial << " final " << final_loss;
}

}  // namespace
}  // namespace moslam::weak
