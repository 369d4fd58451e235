#include "moslam/semantic/dense_crf.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/crf_test_scenes.h"

namespace moslam::semantic {
namespace {

using testing::Planar;
using testing::TwoRegionImage;

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

}  // namespace
}  // namespace moslam::semantic
