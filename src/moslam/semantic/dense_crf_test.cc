#include "moslam/semantic/dense_crf.h"
#include "moslam/testing/error_of.h"

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/crf_test_scenes.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

using ::testing::HasSubstr;
using testing::Planar;
using testing::RandomProbabilities;
using testing::TwoRegionImage;

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

TEST(DenseCrf, ReusedObjectGivesTheResultsOfFreshOnes) {
  // A DenseCrf keeps its buffers between images: sizes, label counts and kernels may change.
  DenseCrfOptions o;
  o.depth = true;
  DenseCrf crf(o);
  struct Input {
    cv::Mat image;
    cv::Mat depth;
    cv::Mat probs;
  };
  std::vector<Input> inputs;
  for (const auto& [rows, cols, labels] :
       {std::tuple{40, 50, 3}, std::tuple{23, 71, 21}, std::tuple{40, 50, 2}}) {
    cv::Mat depth(rows, cols, CV_32F);
    cv::randu(depth, 0.5, 3.0);
    inputs.push_back({TwoRegionImage(rows, cols, 11), depth,
                      RandomProbabilities(labels, rows, cols, static_cast<uint32_t>(labels))});
  }
  CrfResult reused;
  for (int round = 0; round < 2; ++round) {
    for (const Input& in : inputs) {
      crf.Infer(in.image, in.depth, Unaries::FromProbabilities(in.probs), &reused);
      const CrfResult fresh =
          InferDenseCrf(in.image, in.depth, Unaries::FromProbabilities(in.probs), o);
      EXPECT_EQ(cv::countNonZero(reused.marginals.reshape(1, 1) != fresh.marginals.reshape(1, 1)),
                0);
      EXPECT_EQ(cv::countNonZero(reused.labels != fresh.labels), 0);
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
  for (size_t i = 0; i < energies.total(); ++i) {
    float& v = energies.ptr<float>()[i];
    v = -std::log(std::max(v, 1e-5f));
  }
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

using ::moslam::testing::ErrorOf;

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
  moslam::testing::TempDir dir;
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
