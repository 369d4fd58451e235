#include "moslam/semantic/dense_crf.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

using ::testing::HasSubstr;

// Planar {L, H, W} probabilities from per-pixel functions.
cv::Mat Planar(int labels, int rows, int cols) {
  const int sizes[3] = {labels, rows, cols};
  return cv::Mat(3, sizes, CV_32F, cv::Scalar(0));
}

// Random smooth-ish probabilities, normalized per pixel.
cv::Mat RandomProbabilities(int labels, int rows, int cols, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(0.05f, 1.0f);
  cv::Mat probs = Planar(labels, rows, cols);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      float sum = 0.0f;
      for (int l = 0; l < labels; ++l) sum += (probs.at<float>(l, y, x) = uniform(rng));
      for (int l = 0; l < labels; ++l) probs.at<float>(l, y, x) /= sum;
    }
  }
  return probs;
}

// Two colour regions split by a slanted edge, with noise.
cv::Mat TwoRegionImage(int rows, int cols, uint32_t seed) {
  cv::Mat image(rows, cols, CV_8UC3);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 6.0f);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const bool right = x > cols / 2 + (y - rows / 2) / 3;
      const cv::Vec3f base = right ? cv::Vec3f(40, 160, 200) : cv::Vec3f(180, 60, 50);
      for (int c = 0; c < 3; ++c) {
        image.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<uint8_t>(base[c] + noise(rng));
      }
    }
  }
  return image;
}

// ---------------------------------------------------------------------------------------------
// Brute-force mean field: the model of dense_crf.h evaluated with exact Gaussians, O(N^2).

struct BruteKernel {
  double weight = 0.0;
  std::vector<std::vector<double>> features;  // per pixel, divided by the sigmas
  std::vector<bool> active;
  double truncate_xy = 0.0;  // > 0: zero beyond this many sigmas in x or y (separable filter)
};

std::vector<double> BruteForce(const cv::Mat& probs, const std::vector<BruteKernel>& kernels,
                               int iterations, double min_probability) {
  const int labels = probs.size[0];
  const int rows = probs.size[1];
  const int cols = probs.size[2];
  const int n = rows * cols;
  std::vector<double> unary(static_cast<size_t>(n) * labels);
  for (int l = 0; l < labels; ++l) {
    for (int p = 0; p < n; ++p) {
      const double prob = probs.ptr<float>(l)[p];
      unary[p * labels + l] = -std::log(std::clamp(prob, min_probability, 1.0));
    }
  }
  // Normalized kernel matrices times their weights.
  std::vector<std::vector<double>> matrices;
  for (const BruteKernel& k : kernels) {
    std::vector<double> m(static_cast<size_t>(n) * n, 0.0);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        if (!k.active[i] || !k.active[j]) continue;
        if (k.truncate_xy > 0.0 &&
            (std::fabs(k.features[i][0] - k.features[j][0]) > k.truncate_xy + 1e-9 ||
             std::fabs(k.features[i][1] - k.features[j][1]) > k.truncate_xy + 1e-9)) {
          continue;
        }
        double d2 = 0.0;
        for (size_t c = 0; c < k.features[i].size(); ++c) {
          const double d = k.features[i][c] - k.features[j][c];
          d2 += d * d;
        }
        m[static_cast<size_t>(i) * n + j] = std::exp(-0.5 * d2);
      }
    }
    std::vector<double> norm(n, 0.0);
    for (int i = 0; i < n; ++i) {
      double sum = 0.0;
      for (int j = 0; j < n; ++j) sum += m[static_cast<size_t>(i) * n + j];
      norm[i] = sum > 0.0 ? 1.0 / std::sqrt(sum) : 0.0;
    }
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) m[static_cast<size_t>(i) * n + j] *= k.weight * norm[i] * norm[j];
    }
    matrices.push_back(std::move(m));
  }
  std::vector<double> q(static_cast<size_t>(n) * labels);
  const auto softmax = [&](const std::vector<double>& message) {
    for (int i = 0; i < n; ++i) {
      double top = -1e300;
      std::vector<double> a(labels);
      for (int l = 0; l < labels; ++l) {
        a[l] = -unary[i * labels + l] + (message.empty() ? 0.0 : message[i * labels + l]);
        top = std::max(top, a[l]);
      }
      double sum = 0.0;
      for (int l = 0; l < labels; ++l) sum += (a[l] = std::exp(a[l] - top));
      for (int l = 0; l < labels; ++l) q[i * labels + l] = a[l] / sum;
    }
  };
  softmax({});
  for (int it = 0; it < iterations; ++it) {
    std::vector<double> message(static_cast<size_t>(n) * labels, 0.0);
    for (const auto& m : matrices) {
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          const double k = m[static_cast<size_t>(i) * n + j];
          if (k == 0.0) continue;
          for (int l = 0; l < labels; ++l) message[i * labels + l] += k * q[j * labels + l];
        }
      }
    }
    softmax(message);  // Potts: adding m(l) equals subtracting sum_l' [l != l'] m(l')
  }
  return q;
}

BruteKernel PositionKernel(int rows, int cols, double sxy, double weight) {
  BruteKernel k;
  k.weight = weight;
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      k.features.push_back({x / sxy, y / sxy});
      k.active.push_back(true);
    }
  }
  return k;
}

BruteKernel AppearanceKernel(const cv::Mat& image, double sxy, double srgb, double weight) {
  BruteKernel k = PositionKernel(image.rows, image.cols, sxy, weight);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      const cv::Vec3b c = image.at<cv::Vec3b>(y, x);
      for (int i = 0; i < 3; ++i) k.features[y * image.cols + x].push_back(c[i] / srgb);
    }
  }
  return k;
}

BruteKernel DepthKernel(const cv::Mat& depth, double sxy, double sd, double weight) {
  BruteKernel k = PositionKernel(depth.rows, depth.cols, sxy, weight);
  for (int y = 0; y < depth.rows; ++y) {
    for (int x = 0; x < depth.cols; ++x) {
      const float z = depth.at<float>(y, x);
      const bool valid = std::isfinite(z) && z > 0.0f;
      k.features[y * depth.cols + x].push_back(valid ? z / sd : 0.0);
      k.active[y * depth.cols + x] = valid;
    }
  }
  return k;
}

struct Agreement {
  double max_error = 0.0;        // largest marginal difference
  double mean_error = 0.0;       // mean marginal difference
  double label_agreement = 0.0;  // fraction of pixels with the same argmax
};

Agreement Compare(const CrfResult& result, const std::vector<double>& brute) {
  const int labels = result.marginals.size[0];
  const int n = result.marginals.size[1] * result.marginals.size[2];
  Agreement a;
  for (int l = 0; l < labels; ++l) {
    for (int p = 0; p < n; ++p) {
      const double e = std::fabs(result.marginals.ptr<float>(l)[p] - brute[p * labels + l]);
      a.max_error = std::max(a.max_error, e);
      a.mean_error += e / (static_cast<double>(n) * labels);
    }
  }
  for (int p = 0; p < n; ++p) {
    int best = 0;
    for (int l = 1; l < labels; ++l) {
      if (brute[p * labels + l] > brute[p * labels + best]) best = l;
    }
    a.label_agreement += (result.labels.ptr<uint8_t>()[p] == best ? 1.0 : 0.0) / n;
  }
  return a;
}

// A small scene for the brute-force comparisons: 20 x 16 pixels, two colour regions, two depth
// planes with a few holes, and noisy unaries for 3 labels that favour the true label (0 left,
// 1 top right, 2 bottom right) with probability 0.35 to 0.75. (With uniformly random unaries
// and the default weights, mean field sits on knife edges where any difference, float rounding
// included, flips labels: nothing to compare.)
struct SmallScene {
  int rows = 16;
  int cols = 20;
  cv::Mat image = TwoRegionImage(16, 20, 1);
  cv::Mat probs = Planar(3, 16, 20);
  cv::Mat depth;
  SmallScene() {
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> confidence(0.35f, 0.75f);
    std::uniform_real_distribution<float> split(0.0f, 1.0f);
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) {
        const int truth = x < 8 ? 0 : (y < 8 ? 1 : 2);
        const float c = confidence(rng);
        const float r = split(rng) * (1.0f - c);
        probs.at<float>(truth, y, x) = c;
        probs.at<float>((truth + 1) % 3, y, x) = r;
        probs.at<float>((truth + 2) % 3, y, x) = 1.0f - c - r;
      }
    }
    depth.create(rows, cols, CV_32F);
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) depth.at<float>(y, x) = x < 8 ? 1.0f + 0.01f * y : 2.5f;
    }
    depth.at<float>(3, 4) = 0.0f;
    depth.at<float>(10, 15) = std::numeric_limits<float>::quiet_NaN();
    depth.at<float>(7, 8) = -1.0f;
  }
};

TEST(DenseCrf, SeparableSmoothnessMatchesBruteForceExactly) {
  const SmallScene s;
  DenseCrfOptions o;
  o.appearance = false;
  o.smoothness_sxy = 1.5f;
  o.smoothness_weight = 3.0f;
  o.smoothness_filter = "separable";
  const CrfResult result =
      InferDenseCrf(s.image, cv::Mat(), Unaries::FromProbabilities(s.probs), o);
  BruteKernel k = PositionKernel(s.rows, s.cols, 1.5, 3.0);
  k.truncate_xy = std::ceil(3.0 * 1.5) / 1.5;  // the blur's radius, in sigmas
  const auto brute = BruteForce(s.probs, {k}, 5, o.min_probability);
  const Agreement a = Compare(result, brute);
  // Only float rounding and the fast exp/log separate them.
  EXPECT_LT(a.max_error, 1e-4);
}

TEST(DenseCrf, LatticeKernelsAgreeWithBruteForceMeanField) {
  const SmallScene s;
  struct Case {
    std::string name;
    bool smoothness, appearance, depth;
  };
  for (const Case& c :
       {Case{"smoothness", true, false, false}, Case{"appearance", false, true, false},
        Case{"depth", false, false, true}, Case{"all", true, true, true}}) {
    for (int iterations : {1, 5}) {
      DenseCrfOptions o;  // default weights
      o.iterations = iterations;
      o.smoothness = c.smoothness;
      o.smoothness_filter = "lattice";
      o.smoothness_sxy = 1.5f;
      o.appearance = c.appearance;
      o.appearance_sxy = 5.0f;
      o.appearance_srgb = 30.0f;
      o.depth = c.depth;
      o.depth_sxy = 4.0f;
      o.depth_sd_m = 0.3f;
      const CrfResult result =
          InferDenseCrf(s.image, s.depth, Unaries::FromProbabilities(s.probs), o);
      std::vector<BruteKernel> kernels;
      if (c.smoothness) kernels.push_back(PositionKernel(s.rows, s.cols, 1.5, 3.0));
      if (c.appearance) kernels.push_back(AppearanceKernel(s.image, 5.0, 30.0, 10.0));
      if (c.depth) kernels.push_back(DepthKernel(s.depth, 4.0, 0.3, 15.0));
      const Agreement a =
          Compare(result, BruteForce(s.probs, kernels, iterations, o.min_probability));
      if (iterations == 1) {
        // One step: the message error is the lattice's filtering error times the weights.
        EXPECT_LT(a.max_error, 0.1) << c.name;
      } else {
        // Five steps with weights 10 and 15 amplify differences at the few pixels near a
        // decision boundary; on average the marginals still agree closely.
        EXPECT_LT(a.mean_error, 0.015) << c.name;
        EXPECT_GE(a.label_agreement, 0.98) << c.name;
      }
    }
  }
}

TEST(DenseCrf, PairwiseTermsMatterInTheBruteForceScene) {
  // Guards the agreement test above: the pairwise terms change the marginals by much more than
  // the tolerance used there.
  const SmallScene s;
  DenseCrfOptions o;
  o.iterations = 0;
  const CrfResult unary_only =
      InferDenseCrf(s.image, s.depth, Unaries::FromProbabilities(s.probs), o);
  std::vector<BruteKernel> kernels = {PositionKernel(s.rows, s.cols, 1.5, 3.0),
                                      AppearanceKernel(s.image, 5.0, 30.0, 10.0),
                                      DepthKernel(s.depth, 4.0, 0.3, 15.0)};
  const Agreement a = Compare(unary_only, BruteForce(s.probs, kernels, 5, o.min_probability));
  EXPECT_GT(a.mean_error, 0.1);
}

// ---------------------------------------------------------------------------------------------
// Behaviour on synthetic scenes.

double Accuracy(const cv::Mat& labels, const cv::Mat& truth, const cv::Mat& mask) {
  int correct = 0;
  int total = 0;
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      if (!mask.empty() && mask.at<uint8_t>(y, x) == 0) continue;
      correct += labels.at<uint8_t>(y, x) == truth.at<uint8_t>(y, x) ? 1 : 0;
      ++total;
    }
  }
  return static_cast<double>(correct) / total;
}

// Argmax of planar probabilities.
cv::Mat ArgMax(const cv::Mat& probs) {
  cv::Mat labels(probs.size[1], probs.size[2], CV_8U, cv::Scalar(0));
  for (int y = 0; y < labels.rows; ++y) {
    for (int x = 0; x < labels.cols; ++x) {
      for (int l = 1; l < probs.size[0]; ++l) {
        if (probs.at<float>(l, y, x) > probs.at<float>(labels.at<uint8_t>(y, x), y, x)) {
          labels.at<uint8_t>(y, x) = static_cast<uint8_t>(l);
        }
      }
    }
  }
  return labels;
}

TEST(DenseCrf, SnapsANoisyDisplacedUnaryToTheColourEdge) {
  // A bright disc on a dark background; the unary sees a disc shifted by 5 pixels and 3 pixels
  // too large, with per-pixel noise.
  const int rows = 90;
  const int cols = 120;
  cv::Mat image(rows, cols, CV_8UC3, cv::Scalar(40, 50, 60));
  cv::circle(image, {60, 45}, 25, cv::Scalar(200, 190, 160), -1);
  cv::Mat noise(rows, cols, CV_8UC3);
  cv::randu(noise, 0, 10);
  image += noise;
  cv::Mat truth(rows, cols, CV_8U, cv::Scalar(0));
  cv::circle(truth, {60, 45}, 25, cv::Scalar(1), -1);
  cv::Mat probs = Planar(2, rows, cols);
  std::mt19937 rng(4);
  std::normal_distribution<float> jitter(0.0f, 0.2f);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const float inside = std::hypot(x - 65.0f, y - 45.0f) < 28.0f ? 1.0f : -1.0f;
      const float p = std::clamp(0.5f + 0.2f * inside + jitter(rng), 0.02f, 0.98f);
      probs.at<float>(1, y, x) = p;
      probs.at<float>(0, y, x) = 1.0f - p;
    }
  }
  // Pixels within 6 pixels of the true edge.
  cv::Mat near_edge(rows, cols, CV_8U, cv::Scalar(0));
  cv::circle(near_edge, {60, 45}, 25, cv::Scalar(1), 12);
  const CrfResult result =
      InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(probs), DenseCrfOptions());
  const cv::Mat unary_labels = ArgMax(probs);
  EXPECT_LT(Accuracy(unary_labels, truth, cv::Mat()), 0.9);
  EXPECT_LT(Accuracy(unary_labels, truth, near_edge), 0.7);
  EXPECT_GT(Accuracy(result.labels, truth, cv::Mat()), 0.98);
  EXPECT_GT(Accuracy(result.labels, truth, near_edge), 0.9);
}

// An object and a background of the same grey, 1 m and 3 m away; the unary bleeds the object
// 12 pixels into the background. Depth can fix that, colour cannot.
struct SameColourScene {
  int rows = 60;
  int cols = 90;
  cv::Mat image;
  cv::Mat depth;
  cv::Mat truth;
  cv::Mat band;  // where the unary is ambiguous
  cv::Mat probs;
  SameColourScene() {
    image.create(rows, cols, CV_8UC3);
    cv::randu(image, 120, 128);
    depth.create(rows, cols, CV_32F);
    truth.create(rows, cols, CV_8U);
    band.create(rows, cols, CV_8U);
    probs = Planar(2, rows, cols);
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> jitter(-0.05f, 0.05f);
    for (int y = 0; y < rows; ++y) {
      const float edge = 40.0f + 4.0f * std::sin(y / 7.0f);
      for (int x = 0; x < cols; ++x) {
        const bool object = x < edge;
        truth.at<uint8_t>(y, x) = object ? 0 : 1;
        depth.at<float>(y, x) = object ? 1.0f + 0.002f * x : 3.0f - 0.002f * y;
        const bool ambiguous = x >= edge - 12.0f && x < edge + 12.0f;
        band.at<uint8_t>(y, x) = ambiguous ? 1 : 0;
        const float p_object = ambiguous ? 0.62f + jitter(rng) : (object ? 0.8f : 0.2f);
        probs.at<float>(0, y, x) = p_object;
        probs.at<float>(1, y, x) = 1.0f - p_object;
      }
    }
  }
};

TEST(DenseCrf, DepthSeparatesObjectsThatColourCannot) {
  const SameColourScene s;
  DenseCrfOptions colour;  // the paper's "c": smoothness + appearance
  DenseCrfOptions depth;   // the paper's "d": smoothness + depth
  depth.appearance = false;
  depth.depth = true;
  const auto unaries = Unaries::FromProbabilities(s.probs);
  const CrfResult with_colour = InferDenseCrf(s.image, s.depth, unaries, colour);
  const CrfResult with_depth = InferDenseCrf(s.image, s.depth, unaries, depth);
  EXPECT_LT(Accuracy(ArgMax(s.probs), s.truth, s.band), 0.6);
  EXPECT_LT(Accuracy(with_colour.labels, s.truth, s.band), 0.75);
  EXPECT_GT(Accuracy(with_depth.labels, s.truth, s.band), 0.95);
  EXPECT_GT(Accuracy(with_depth.labels, s.truth, cv::Mat()), 0.98);
}

TEST(DenseCrf, InvalidDepthNeitherPullsNorIsPulledThroughTheDepthKernel) {
  SameColourScene s;
  // Holes of each kind of invalid depth, inside the object next to the edge.
  s.depth(cv::Rect(25, 10, 10, 10)).setTo(0.0f);
  s.depth(cv::Rect(25, 30, 10, 10)).setTo(std::numeric_limits<float>::quiet_NaN());
  s.depth(cv::Rect(25, 45, 10, 10)).setTo(-2.0f);
  cv::Mat invalid(s.rows, s.cols, CV_8U);
  for (int y = 0; y < s.rows; ++y) {
    for (int x = 0; x < s.cols; ++x) {
      const float z = s.depth.at<float>(y, x);
      invalid.at<uint8_t>(y, x) = std::isfinite(z) && z > 0.0f ? 0 : 255;
    }
  }
  DenseCrfOptions o;  // the depth kernel alone
  o.smoothness = false;
  o.appearance = false;
  o.depth = true;
  const CrfResult before = InferDenseCrf(s.image, s.depth, Unaries::FromProbabilities(s.probs), o);
  // Invalid pixels keep their unary: softmax(-U) = the (normalized, clamped) probabilities.
  for (int y = 0; y < s.rows; ++y) {
    for (int x = 0; x < s.cols; ++x) {
      for (int l = 0; l < 2; ++l) {
        const float q = before.marginals.at<float>(l, y, x);
        ASSERT_TRUE(std::isfinite(q));
        if (invalid.at<uint8_t>(y, x) != 0) {
          EXPECT_NEAR(q, s.probs.at<float>(l, y, x), 1e-5);
        }
      }
    }
  }
  // Whatever the invalid pixels' unaries say, valid pixels do not notice.
  cv::Mat changed = s.probs.clone();
  for (int y = 0; y < s.rows; ++y) {
    for (int x = 0; x < s.cols; ++x) {
      if (invalid.at<uint8_t>(y, x) == 0) continue;
      changed.at<float>(0, y, x) = 0.001f;
      changed.at<float>(1, y, x) = 0.999f;
    }
  }
  const CrfResult after = InferDenseCrf(s.image, s.depth, Unaries::FromProbabilities(changed), o);
  int compared = 0;
  for (int y = 0; y < s.rows; ++y) {
    for (int x = 0; x < s.cols; ++x) {
      if (invalid.at<uint8_t>(y, x) != 0) continue;
      ASSERT_EQ(before.marginals.at<float>(0, y, x), after.marginals.at<float>(0, y, x))
          << x << "," << y;
      ++compared;
    }
  }
  EXPECT_EQ(compared, s.rows * s.cols - 300);
  // And the depth kernel still fixes the valid part of the bleeding band.
  EXPECT_GT(Accuracy(before.labels, s.truth, s.band & ~invalid), 0.95);
}

TEST(DenseCrf, OutputDoesNotDependOnTheNumberOfThreads) {
  const cv::Mat image = TwoRegionImage(53, 67, 3);
  cv::Mat depth(53, 67, CV_32F);
  cv::randu(depth, 0.5, 4.0);
  depth(cv::Rect(3, 3, 5, 5)).setTo(0.0f);
  for (int labels : {2, 5, 21}) {
    const auto unaries = Unaries::FromProbabilities(RandomProbabilities(labels, 53, 67, labels));
    std::vector<CrfResult> results;
    for (int threads : {1, 2, 3}) {
      DenseCrfOptions o;
      o.depth = true;
      o.num_threads = threads;
      results.push_back(InferDenseCrf(image, depth, unaries, o));
    }
    for (size_t i = 1; i < results.size(); ++i) {
      const cv::Mat a = results[0].marginals.reshape(1, 1);
      const cv::Mat b = results[i].marginals.reshape(1, 1);
      EXPECT_EQ(cv::countNonZero(a != b), 0) << labels << " labels";
      EXPECT_EQ(cv::countNonZero(results[0].labels != results[i].labels), 0);
    }
  }
}

void ExpectValidResult(const CrfResult& r, const std::string& what) {
  const int labels = r.marginals.size[0];
  for (int y = 0; y < r.labels.rows; ++y) {
    for (int x = 0; x < r.labels.cols; ++x) {
      float sum = 0.0f;
      int best = 0;
      for (int l = 0; l < labels; ++l) {
        const float q = r.marginals.at<float>(l, y, x);
        ASSERT_TRUE(std::isfinite(q) && q >= 0.0f) << what;
        sum += q;
        if (q > r.marginals.at<float>(best, y, x)) best = l;
      }
      ASSERT_NEAR(sum, 1.0f, 1e-4f) << what;
      ASSERT_EQ(r.labels.at<uint8_t>(y, x), best) << what;
    }
  }
}

TEST(DenseCrf, HandlesAnySizeGreyImagesAndUpTo32Labels) {
  for (const cv::Size size :
       {cv::Size(1, 1), cv::Size(9, 1), cv::Size(1, 9), cv::Size(7, 5), cv::Size(17, 13)}) {
    for (int labels : {2, 3, 6, 32}) {
      for (bool grey : {false, true}) {
        cv::Mat image = TwoRegionImage(size.height, size.width, 5);
        if (grey) cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
        cv::Mat depth(size, CV_32F, cv::Scalar(2.0f));
        DenseCrfOptions o;
        o.depth = true;
        const std::string what = std::to_string(size.width) + "x" + std::to_string(size.height) +
                                 " L=" + std::to_string(labels) + (grey ? " grey" : " colour");
        ExpectValidResult(InferDenseCrf(image, depth,
                                        Unaries::FromProbabilities(RandomProbabilities(
                                            labels, size.height, size.width, 7)),
                                        o),
                          what);
      }
    }
  }
}

TEST(DenseCrf, GreyImagesUseIntensityInTheAppearanceKernel) {
  // The disc scene in grey: the appearance kernel must still find the edge.
  cv::Mat image(60, 80, CV_8U, cv::Scalar(50));
  cv::circle(image, {40, 30}, 15, cv::Scalar(200), -1);
  cv::Mat truth(60, 80, CV_8U, cv::Scalar(0));
  cv::circle(truth, {40, 30}, 15, cv::Scalar(1), -1);
  cv::Mat probs = Planar(2, 60, 80);
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 80; ++x) {
      const float p = std::hypot(x - 44.0f, y - 30.0f) < 18.0f ? 0.65f : 0.35f;
      probs.at<float>(1, y, x) = p;
      probs.at<float>(0, y, x) = 1.0f - p;
    }
  }
  const CrfResult r =
      InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(probs), DenseCrfOptions());
  EXPECT_LT(Accuracy(ArgMax(probs), truth, cv::Mat()), 0.95);
  EXPECT_GT(Accuracy(r.labels, truth, cv::Mat()), 0.99);
}

TEST(DenseCrf, UnaryFormsAndLayoutsAgree) {
  const cv::Mat image = TwoRegionImage(21, 30, 6);
  cv::Mat probs = RandomProbabilities(4, 21, 30, 8);
  probs.at<float>(2, 3, 3) = 0.0f;  // clamped to min_probability
  const DenseCrfOptions o;
  const CrfResult from_probs =
      InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(probs), o);
  ExpectValidResult(from_probs, "probabilities");
  // Energies -log(max(p, min_probability)).
  cv::Mat energies = probs.clone();
  energies.forEach<float>([&](float& v, const int*) { v = -std::log(std::max(v, 1e-5f)); });
  const CrfResult from_energies =
      InferDenseCrf(image, cv::Mat(), Unaries::FromEnergies(energies), o);
  double worst = 0.0;
  for (size_t i = 0; i < probs.total(); ++i) {
    worst = std::max<double>(worst, std::fabs(from_probs.marginals.ptr<float>()[i] -
                                              from_energies.marginals.ptr<float>()[i]));
  }
  EXPECT_LT(worst, 1e-4);
  // Interleaved H x W x L gives exactly the planar result.
  std::vector<cv::Mat> planes;
  for (int l = 0; l < 4; ++l) planes.push_back(LabelPlane(probs, l));
  cv::Mat interleaved;
  cv::merge(planes, interleaved);
  const CrfResult from_interleaved =
      InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(interleaved), o);
  EXPECT_EQ(cv::countNonZero(from_probs.marginals.reshape(1, 1) !=
                             from_interleaved.marginals.reshape(1, 1)),
            0);
}

TEST(DenseCrf, ZeroIterationsGiveTheNormalizedUnaries) {
  const cv::Mat image = TwoRegionImage(10, 12, 6);
  const cv::Mat probs = RandomProbabilities(3, 10, 12, 10);
  DenseCrfOptions o;
  o.iterations = 0;
  const CrfResult r = InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(probs), o);
  for (size_t i = 0; i < probs.total(); ++i) {
    EXPECT_NEAR(r.marginals.ptr<float>()[i], probs.ptr<float>()[i], 2e-6f);
  }
}

TEST(DenseCrf, CompatibilityMatrix) {
  const cv::Mat image = TwoRegionImage(20, 24, 6);
  const auto unaries = Unaries::FromProbabilities(RandomProbabilities(3, 20, 24, 12));
  DenseCrfOptions potts;
  DenseCrfOptions explicit_potts;
  explicit_potts.compatibility = {0, 1, 1, 1, 0, 1, 1, 1, 0};
  DenseCrfOptions none;  // no penalty at all: mean field keeps the unaries
  none.compatibility = std::vector<double>(9, 0.0);
  DenseCrfOptions unary_only;
  unary_only.iterations = 0;
  const CrfResult a = InferDenseCrf(image, cv::Mat(), unaries, potts);
  const CrfResult b = InferDenseCrf(image, cv::Mat(), unaries, explicit_potts);
  const CrfResult c = InferDenseCrf(image, cv::Mat(), unaries, none);
  const CrfResult d = InferDenseCrf(image, cv::Mat(), unaries, unary_only);
  double potts_difference = 0.0;
  double none_difference = 0.0;
  double crf_effect = 0.0;
  for (size_t i = 0; i < a.marginals.total(); ++i) {
    potts_difference = std::max<double>(
        potts_difference, std::fabs(a.marginals.ptr<float>()[i] - b.marginals.ptr<float>()[i]));
    none_difference = std::max<double>(
        none_difference, std::fabs(c.marginals.ptr<float>()[i] - d.marginals.ptr<float>()[i]));
    crf_effect = std::max<double>(
        crf_effect, std::fabs(a.marginals.ptr<float>()[i] - d.marginals.ptr<float>()[i]));
  }
  EXPECT_LT(potts_difference, 1e-4);
  EXPECT_LT(none_difference, 1e-6);
  EXPECT_GT(crf_effect, 0.3);
}

// ---------------------------------------------------------------------------------------------
// Options and input errors.

template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InputError";
  return {};
}

TEST(DenseCrfOptions, DefaultsAreValidAndBadValuesAreNamed) {
  EXPECT_NO_THROW(DenseCrfOptions().Check());
  DenseCrfOptions o;
  o.appearance_srgb = 0.0f;
  EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr("appearance_srgb"));
  o = DenseCrfOptions();
  o.depth_weight = -1.0f;
  EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr("depth_weight"));
  o = DenseCrfOptions();
  o.iterations = -1;
  EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr("iterations"));
  o = DenseCrfOptions();
  o.compatibility = {0, 1, 1};
  EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr("compatibility"));
  o = DenseCrfOptions();
  o.smoothness_filter = "fft";
  EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr("smoothness_filter"));
  o = DenseCrfOptions();
  o.num_threads = 0;
  EXPECT_THAT(ErrorOf([&] { DenseCrf crf(o); }), HasSubstr("num_threads"));
}

TEST(DenseCrfOptions, LoadsFromYamlAndRejectsUnknownKeys) {
  testing::TempDir dir;
  const std::string good = dir.Write("crf.yaml",
                                     "%YAML:1.0\n"
                                     "crf:\n"
                                     "  iterations: 8\n"
                                     "  depth: true\n"
                                     "  depth_sd_m: 0.25\n"
                                     "  appearance_weight: 4\n"
                                     "  smoothness_filter: lattice\n"
                                     "  compatibility: [0, 2, 2, 0]\n");
  const DenseCrfOptions o = LoadDenseCrfOptions(good);
  EXPECT_EQ(o.iterations, 8);
  EXPECT_TRUE(o.depth);
  EXPECT_FLOAT_EQ(o.depth_sd_m, 0.25f);
  EXPECT_FLOAT_EQ(o.appearance_weight, 4.0f);
  EXPECT_EQ(o.smoothness_filter, "lattice");
  EXPECT_EQ(o.compatibility, (std::vector<double>{0, 2, 2, 0}));
  EXPECT_FLOAT_EQ(o.smoothness_sxy, 3.0f);  // default kept
  const std::string typo = dir.Write("typo.yaml", "%YAML:1.0\ncrf:\n  apperance_weight: 4\n");
  EXPECT_THAT(ErrorOf([&] { LoadDenseCrfOptions(typo); }), HasSubstr("apperance_weight"));
  const std::string bad = dir.Write("bad.yaml", "%YAML:1.0\ncrf:\n  smoothness_sxy: -3\n");
  EXPECT_THAT(ErrorOf([&] { LoadDenseCrfOptions(bad); }), HasSubstr("bad.yaml"));
}

TEST(DenseCrf, RejectsInconsistentInputs) {
  const cv::Mat image = TwoRegionImage(10, 12, 6);
  const cv::Mat probs = RandomProbabilities(3, 10, 12, 10);
  const DenseCrfOptions o;
  EXPECT_THAT(ErrorOf([&] {
                InferDenseCrf(image(cv::Rect(0, 0, 11, 10)), cv::Mat(),
                              Unaries::FromProbabilities(probs), o);
              }),
              HasSubstr("unaries are 12x10"));
  cv::Mat image16;
  image.convertTo(image16, CV_16UC3);
  EXPECT_THAT(
      ErrorOf([&] { InferDenseCrf(image16, cv::Mat(), Unaries::FromProbabilities(probs), o); }),
      HasSubstr("8-bit"));
  EXPECT_THAT(ErrorOf([&] {
                InferDenseCrf(image, cv::Mat(),
                              Unaries::FromProbabilities(RandomProbabilities(1, 10, 12, 1)), o);
              }),
              HasSubstr("1 labels"));
  EXPECT_THAT(ErrorOf([&] {
                InferDenseCrf(image, cv::Mat(),
                              Unaries::FromProbabilities(RandomProbabilities(33, 10, 12, 1)), o);
              }),
              HasSubstr("33 labels"));
  cv::Mat nan_probs = probs.clone();
  nan_probs.at<float>(1, 2, 3) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THAT(
      ErrorOf([&] { InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(nan_probs), o); }),
      HasSubstr("not finite"));
  DenseCrfOptions with_depth;
  with_depth.depth = true;
  EXPECT_THAT(ErrorOf([&] {
                InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(probs), with_depth);
              }),
              HasSubstr("no depth"));
  EXPECT_THAT(ErrorOf([&] {
                InferDenseCrf(image, cv::Mat(10, 12, CV_16U, cv::Scalar(1000)),
                              Unaries::FromProbabilities(probs), with_depth);
              }),
              HasSubstr("CV_32F"));
  DenseCrfOptions compat;
  compat.compatibility = {0, 1, 1, 0};
  EXPECT_THAT(
      ErrorOf([&] { InferDenseCrf(image, cv::Mat(), Unaries::FromProbabilities(probs), compat); }),
      HasSubstr("compatibility"));
}

}  // namespace
}  // namespace moslam::semantic
