// The post-processing of the mask providers on hand-made probabilities: no network needed.
#include "moslam/semantic/mask_refine.h"

#include <cmath>

#include <gtest/gtest.h>

#include "moslam/semantic/box_detector.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

// Planar {3, h, w} probabilities for classes background (0), person (1), tree (2): person on the
// left `person_cols` columns, background elsewhere, and tree at `tree_max` on scattered pixels.
cv::Mat Probabilities(const cv::Size& size, int person_cols, float tree_max) {
  const int sizes[3] = {3, size.height, size.width};
  cv::Mat p(3, sizes, CV_32F, cv::Scalar(0));
  for (int y = 0; y < size.height; ++y) {
    for (int x = 0; x < size.width; ++x) {
      const bool person = x < person_cols;
      const float tree = (x + y) % 7 == 0 ? tree_max : 0.0f;
      p.at<float>(0, y, x) = (person ? 0.2f : 0.8f) * (1.0f - tree);
      p.at<float>(1, y, x) = (person ? 0.8f : 0.2f) * (1.0f - tree);
      p.at<float>(2, y, x) = tree;
    }
  }
  return p;
}

TEST(MaskRefine, WorkingSizeKeepsAspectAndNeverUpsamples) {
  EXPECT_EQ(WorkingSize(cv::Size(640, 480), 320), cv::Size(320, 240));
  EXPECT_EQ(WorkingSize(cv::Size(1226, 370), 320), cv::Size(320, 97));
  EXPECT_EQ(WorkingSize(cv::Size(200, 100), 320), cv::Size(200, 100));
  EXPECT_EQ(WorkingSize(cv::Size(640, 480), 0), cv::Size(640, 480));
}

TEST(MaskRefine, SoftmaxSumsToOneAndKeepsTheArgmax) {
  const int sizes[3] = {3, 2, 2};
  cv::Mat logits(3, sizes, CV_32F);
  const float values[12] = {1, 50, -3, 0, 2, 49, -2, 0, 0, 0, 10, 0};
  std::copy(values, values + 12, logits.ptr<float>());
  SoftmaxPlanar(&logits);
  for (int i = 0; i < 4; ++i) {
    const float* p = logits.ptr<float>();
    EXPECT_NEAR(p[i] + p[4 + i] + p[8 + i], 1.0f, 1e-6f);
  }
  const cv::Mat labels = ArgMaxPlanar(logits);
  EXPECT_EQ(labels.at<uint8_t>(0, 0), 1);
  EXPECT_EQ(labels.at<uint8_t>(0, 1), 0);
  EXPECT_EQ(labels.at<uint8_t>(1, 0), 2);
}

TEST(MaskRefine, MovableClassesBecome255AtTheImageSize) {
  const cv::Mat image(60, 80, CV_8UC3, cv::Scalar(90, 90, 90));
  RefineOptions options;
  options.working_side = 40;  // 40 x 30
  MaskRefiner refiner(options, {false, true, false}, 0);
  const RefineResult r = refiner.Refine(Probabilities(cv::Size(40, 30), 10, 0.0f), image, {});
  ASSERT_EQ(r.mask.size(), image.size());
  ASSERT_EQ(r.mask.type(), CV_8UC1);
  // Left quarter movable (255), the rest static (0), apart from the interpolated boundary.
  EXPECT_EQ(r.mask.at<uint8_t>(30, 5), 255);
  EXPECT_EQ(r.mask.at<uint8_t>(30, 60), 0);
  EXPECT_NEAR(cv::countNonZero(r.mask), 20 * 60, 2 * 60);
  EXPECT_EQ(cv::countNonZero((r.mask != 0) & (r.mask != 255)), 0);
  EXPECT_EQ(r.labels.size(), cv::Size(40, 30));
}

TEST(MaskRefine, WeakClassesAreSuppressedButNotTheBackground) {
  const cv::Mat image(30, 40, CV_8UC1, cv::Scalar(100));
  RefineOptions options;
  options.suppress_below = 0.5f;
  // No person anywhere (its maximum is 0.2); a movable tree peaks at 0.7 on scattered pixels.
  MaskRefiner with(options, {false, true, true}, 0);
  const cv::Mat probs = Probabilities(cv::Size(40, 30), 0, 0.7f);
  options.suppress_below = 0.75f;
  MaskRefiner strict(options, {false, true, true}, 0);
  const RefineResult kept = with.Refine(probs.clone(), image, {});
  EXPECT_GT(cv::countNonZero(kept.mask), 0) << "tree (0.7 >= 0.5) is kept and movable";
  EXPECT_TRUE(kept.suppressed == std::vector<int>{1}) << "person (max 0.2) is suppressed";
  const RefineResult gone = strict.Refine(probs.clone(), image, {});
  EXPECT_EQ(cv::countNonZero(gone.mask), 0);
  EXPECT_EQ(gone.suppressed, (std::vector<int>{1, 2}));
  EXPECT_FLOAT_EQ(gone.image_scores[2], 0.7f);
  // Suppressed mass goes to the remaining classes: probabilities still sum to 1.
  for (int y = 0; y < 30; y += 7) {
    float sum = 0.0f;
    for (int l = 0; l < 3; ++l) sum += gone.probabilities.at<float>(l, y, 3);
    EXPECT_NEAR(sum, 1.0f, 1e-5f);
  }
}

TEST(MaskRefine, MovableBiasMovesTheDecisionThreshold) {
  const cv::Mat image(30, 40, CV_8UC1, cv::Scalar(100));
  // Person at 0.8 on the left 10 columns, 0.2 elsewhere; no tree.
  const cv::Mat probs = Probabilities(cv::Size(40, 30), 10, 0.0f);
  const auto movable_pixels = [&](float bias) {
    RefineOptions options;
    options.working_side = 0;
    options.movable_bias = bias;
    MaskRefiner refiner(options, {false, true, false}, 0);
    return cv::countNonZero(refiner.Refine(probs.clone(), image, {}).mask);
  };
  // Two labels: movable where p > 1 / (1 + exp(bias)): 0.73 at -1, 0.82 at -1.5, 0.18 at +1.5.
  EXPECT_EQ(movable_pixels(0.0f), 10 * 30);
  EXPECT_EQ(movable_pixels(-1.0f), 10 * 30);
  EXPECT_EQ(movable_pixels(-1.5f), 0);
  EXPECT_EQ(movable_pixels(1.5f), 40 * 30);

  RefineOptions options;
  options.working_side = 0;
  options.movable_bias = -1.0f;
  MaskRefiner refiner(options, {false, true, false}, 0);
  const RefineResult r = refiner.Refine(probs.clone(), image, {});
  // exp(-1) * 0.8 against 0.2, renormalized: 0.5954 person on the left, still summing to 1.
  const float person = 0.8f * std::exp(-1.0f) / (0.8f * std::exp(-1.0f) + 0.2f);
  EXPECT_NEAR(r.probabilities.at<float>(1, 5, 3), person, 1e-5f);
  EXPECT_NEAR(r.probabilities.at<float>(0, 5, 3), 1.0f - person, 1e-5f);
  EXPECT_EQ(r.labels.at<uint8_t>(5, 3), 1);

  options.movable_bias = std::nanf("");
  EXPECT_THROW(options.Check(), InputError);
  options.movable_bias = 11.0f;
  EXPECT_THROW(options.Check(), InputError);
}

TEST(MaskRefine, GivenImageScoresDecideTheSuppression) {
  const cv::Mat image(30, 40, CV_8UC1, cv::Scalar(100));
  RefineOptions options;
  options.suppress_below = 0.5f;
  MaskRefiner refiner(options, {false, true, false}, 0);
  const cv::Mat probs = Probabilities(cv::Size(40, 30), 10, 0.0f);  // person at 0.8 on the left
  // A network's image-level score says there is no person (0.1), whatever the pixels say.
  const RefineResult r = refiner.Refine(probs.clone(), image, {}, {0.0f, 0.1f, 0.9f});
  EXPECT_EQ(r.suppressed, (std::vector<int>{1}));
  EXPECT_EQ(cv::countNonZero(r.mask), 0);
  EXPECT_FLOAT_EQ(r.image_scores[1], 0.1f);
  const RefineResult kept = refiner.Refine(probs.clone(), image, {}, {0.0f, 0.6f, 0.0f});
  EXPECT_EQ(kept.suppressed, (std::vector<int>{2}));
  EXPECT_GT(cv::countNonZero(kept.mask), 0);
  EXPECT_THROW(refiner.Refine(probs.clone(), image, {}, {0.5f}), InputError);
}

TEST(MaskRefine, ColourCrfSnapsAnUncertainMaskToTheObject) {
  // A bright square on a dark image; the network's person score is a blurry blob that spills
  // around the square. The colour kernel pulls the mask to the square's edges.
  cv::Mat image(60, 60, CV_8UC3, cv::Scalar(30, 30, 30));
  image(cv::Rect(20, 20, 20, 20)).setTo(cv::Scalar(220, 220, 220));
  const int sizes[3] = {2, 60, 60};
  cv::Mat probs(3, sizes, CV_32F);
  for (int y = 0; y < 60; ++y) {
    for (int x = 0; x < 60; ++x) {
      const float d = std::hypot(x - 30.0f, y - 30.0f);
      const float person = d < 16.0f ? 0.6f : 0.3f;
      probs.at<float>(1, y, x) = person;
      probs.at<float>(0, y, x) = 1.0f - person;
    }
  }
  RefineOptions none;
  none.working_side = 0;
  MaskRefiner plain(none, {false, true}, 0);
  RefineOptions c = none;
  c.crf = CrfMode::kColour;
  MaskRefiner crf(c, {false, true}, 0);
  const cv::Mat truth = cv::Mat::zeros(60, 60, CV_8U);
  truth(cv::Rect(20, 20, 20, 20)).setTo(255);
  const RefineResult before = plain.Refine(probs.clone(), image, {});
  const RefineResult after = crf.Refine(probs.clone(), image, {});
  EXPECT_LT(cv::countNonZero(after.mask != truth), cv::countNonZero(before.mask != truth));
  EXPECT_GT(after.crf_ms, 0.0);
  EXPECT_EQ(before.crf_ms, 0.0);
}

TEST(MaskRefine, DepthCrfNeedsDepthAndDilationGrowsTheMask) {
  const cv::Mat image(30, 40, CV_8UC3, cv::Scalar(50, 60, 70));
  RefineOptions d;
  d.crf = CrfMode::kDepth;
  MaskRefiner refiner(d, {false, true, false}, 0);
  EXPECT_THROW(refiner.Refine(Probabilities(cv::Size(40, 30), 10, 0.0f), image, {}), InputError);
  const cv::Mat depth(30, 40, CV_32F, cv::Scalar(2.0f));
  EXPECT_EQ(refiner.Refine(Probabilities(cv::Size(40, 30), 10, 0.0f), image, depth).mask.size(),
            image.size());
  RefineOptions plain, dilated;
  dilated.dilate_px = 3;
  const int base =
      cv::countNonZero(MaskRefiner(plain, {false, true, false}, 0)
                           .Refine(Probabilities(cv::Size(40, 30), 10, 0.0f), image, {})
                           .mask);
  const int grown =
      cv::countNonZero(MaskRefiner(dilated, {false, true, false}, 0)
                           .Refine(Probabilities(cv::Size(40, 30), 10, 0.0f), image, {})
                           .mask);
  EXPECT_EQ(grown, base + 3 * 30);
}

TEST(MaskRefine, ParsesCrfModes) {
  EXPECT_EQ(ParseCrfMode("none"), CrfMode::kNone);
  EXPECT_EQ(ParseCrfMode("c"), CrfMode::kColour);
  EXPECT_EQ(ParseCrfMode("d"), CrfMode::kDepth);
  EXPECT_EQ(ParseCrfMode("c,d"), CrfMode::kColourDepth);
  EXPECT_EQ(ParseCrfMode("cd"), CrfMode::kColourDepth);
  EXPECT_FALSE(ParseCrfMode("x"));
}

TEST(BoxDetector, BoxesOfMovableClassesBecomeTheMask) {
  // Card classes: person (0), car (1), chair (2); planes: static, person, car.
  const std::vector<int> plane_of = {1, 2, 0};
  const std::vector<Detection> detections = {{0, 0.9f, cv::Rect(10, 10, 20, 40)},
                                             {2, 0.8f, cv::Rect(60, 10, 20, 20)},
                                             {1, 0.4f, cv::Rect(20, 30, 30, 20)}};
  const cv::Size image(100, 80);
  const cv::Mat probs =
      BoxDetector::BoxProbabilities(detections, plane_of, 3, 0.9f, image, cv::Size(50, 40));
  ASSERT_EQ(probs.size[0], 3);
  RefineOptions options;
  options.working_side = 50;
  MaskRefiner refiner(options, {false, true, true}, 0);
  const RefineResult r = refiner.Refine(probs, cv::Mat(image, CV_8UC1, cv::Scalar(0)), {});
  ASSERT_EQ(r.mask.size(), image);
  EXPECT_EQ(r.mask.at<uint8_t>(20, 15), 255);  // inside the person box
  EXPECT_EQ(r.mask.at<uint8_t>(45, 45), 255);  // inside the car box
  EXPECT_EQ(r.mask.at<uint8_t>(20, 70), 0);    // the chair is not movable
  EXPECT_EQ(r.mask.at<uint8_t>(70, 90), 0);    // no box
  cv::Mat expected = cv::Mat::zeros(image, CV_8U);
  expected(cv::Rect(10, 10, 20, 40)).setTo(255);
  expected(cv::Rect(20, 30, 30, 20)).setTo(255);
  EXPECT_EQ(cv::countNonZero(r.mask != expected), 0);
  EXPECT_EQ(r.labels.at<uint8_t>(10, 10), 1);  // person plane (working size)
  EXPECT_EQ(r.labels.at<uint8_t>(20, 20), 2);  // car plane
}

}  // namespace
}  // namespace moslam::semantic
