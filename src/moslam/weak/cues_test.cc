#include "moslam/weak/cues.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::weak {
namespace {

constexpr int kSide = 128;
constexpr int kClasses = 4;
const cv::Point2f kCentre(60.0f, 66.0f);
constexpr float kRadius = 28.0f;

// A red disc on a green-grey textured background, with noise on both.
cv::Mat DiscImage() {
  cv::Mat image(kSide, kSide, CV_8UC3);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(-10, 10);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const bool inside = std::hypot(x - kCentre.x, y - kCentre.y) <= kRadius;
      // Background texture: stripes plus noise, so superpixels cannot be trivial squares.
      const int stripe = ((x / 5 + y / 7) % 2) * 25;
      const cv::Vec3i base = inside ? cv::Vec3i(40, 40, 200) : cv::Vec3i(90 + stripe, 140, 100);
      cv::Vec3b& p = image.at<cv::Vec3b>(y, x);
      for (int k = 0; k < 3; ++k) p[k] = cv::saturate_cast<uchar>(base[k] + noise(rng));
    }
  }
  return image;
}

bool InsideDisc(int x, int y, float margin) {
  return std::hypot(x - kCentre.x, y - kCentre.y) <= kRadius + margin;
}

// CAMs {kClasses, kSide, kSide}: class 2 a blurry Gaussian peaked inside the disc (off its centre)
// whose half-maximum level lies `spill` pixels beyond the disc's boundary; class 3 (not present in
// the image-level labels) a strong blob in a corner; classes 0 and 1 negative everywhere.
cv::Mat Cams(float spill = 5.0f) {
  const int sizes[] = {kClasses, kSide, kSide};
  cv::Mat cams(3, sizes, CV_32F, cv::Scalar(0));
  const float half_max_radius = kRadius + spill;
  const float sigma = half_max_radius / std::sqrt(2.0f * std::log(2.0f));
  const cv::Point2f peak = kCentre + cv::Point2f(3.0f, -2.0f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> negative(-0.5f, -0.01f);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const float d2 = (x - peak.x) * (x - peak.x) + (y - peak.y) * (y - peak.y);
      cams.at<float>(2, y, x) = 5.0f * std::exp(-d2 / (2.0f * sigma * sigma));
      cams.at<float>(3, y, x) =
          9.0f * std::exp(-((x - 120) * (x - 120) + (y - 8) * (y - 8)) / 200.0f);
      cams.at<float>(0, y, x) = negative(rng);
      cams.at<float>(1, y, x) = negative(rng);
    }
  }
  return cams;
}

struct Counts {
  int inside = 0;           // class-2 seeds inside the disc
  int outside = 0;          // class-2 seeds outside the disc
  int far_outside = 0;      // class-2 seeds more than 2 px outside the disc
  int disc_interior = 0;    // pixels at least 3 px inside the disc
  int interior_seeded = 0;  // of those, seeded with class 2
};

Counts Count(const cv::Mat& seeds) {
  Counts c;
  for (int y = 0; y < seeds.rows; ++y) {
    for (int x = 0; x < seeds.cols; ++x) {
      const bool fg = seeds.at<uchar>(y, x) == 2;
      if (InsideDisc(x, y, 0.0f)) {
        c.inside += fg;
      } else {
        c.outside += fg;
      }
      c.far_outside += fg && !InsideDisc(x, y, 2.0f);
      if (InsideDisc(x, y, -3.0f)) {
        ++c.disc_interior;
        c.interior_seeded += fg;
      }
    }
  }
  return c;
}

int CountLabel(const cv::Mat& seeds, int label) { return cv::countNonZero(seeds == label); }

TEST(Cues, SuperpixelsKeepSeedsInsideTheObject) {
  const cv::Mat image = DiscImage();
  const CueOptions options;
  for (float spill : {3.0f, 5.0f}) {
    SCOPED_TRACE(spill);
    const cv::Mat raw = SeedsFromCams(Cams(spill), {1, 2}, -1, options);
    const Counts before = Count(raw);
    // Precondition: the CAM's seeds spill over the disc's boundary.
    ASSERT_GT(before.far_outside, 300);

    const cv::Mat refined = RefineWithSuperpixels(raw, image, options);
    const Counts after = Count(refined);
    // Superpixels follow the disc's edge to within a pixel or two.
    EXPECT_EQ(after.far_outside, 0);
    EXPECT_GE(after.inside, 0.98 * (after.inside + after.outside));
    EXPECT_GE(after.interior_seeded, 0.9 * after.disc_interior);
    // Class 1's CAM is never positive and class 3 is not present: neither gets seeds; without a
    // background class nothing else is labelled.
    EXPECT_EQ(CountLabel(refined, 1) + CountLabel(raw, 1), 0);
    EXPECT_EQ(CountLabel(refined, 3) + CountLabel(raw, 3), 0);
    EXPECT_EQ(CountLabel(refined, 2) + CountLabel(refined, kUnknown), kSide * kSide);
  }
}

TEST(Cues, SuperpixelsWithConflictingOrSparseSeedsAreDropped) {
  const cv::Mat image = DiscImage();
  const CueOptions options;
  // Two labels in a fine checkerboard: every superpixel straddles both.
  cv::Mat checker(kSide, kSide, CV_8UC1);
  // Label 1 everywhere but one pixel in eight: each superpixel agrees and is well covered.
  cv::Mat mostly(kSide, kSide, CV_8UC1);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      checker.at<uchar>(y, x) = (x + y) % 2;
      mostly.at<uchar>(y, x) = (x + 3 * y) % 8 == 0 ? kUnknown : 1;
    }
  }
  EXPECT_EQ(CountLabel(RefineWithSuperpixels(checker, image, options), kUnknown), kSide * kSide);
  EXPECT_EQ(CountLabel(RefineWithSuperpixels(mostly, image, options), 1), kSide * kSide);
  // Sparse seeds (one pixel in eight) cover too little of any superpixel.
  cv::Mat sparse(kSide, kSide, CV_8UC1, cv::Scalar(kUnknown));
  sparse.setTo(1, mostly == kUnknown);
  EXPECT_EQ(CountLabel(RefineWithSuperpixels(sparse, image, options), kUnknown), kSide * kSide);
}

TEST(Cues, BackgroundSeedsOnlyWithABackgroundClass) {
  const cv::Mat cams = Cams();
  const CueOptions options;
  const cv::Mat without = SeedsFromCams(cams, {2}, -1, options);
  EXPECT_EQ(CountLabel(without, 0), 0);
  EXPECT_EQ(CountLabel(without, 2) + CountLabel(without, kUnknown), kSide * kSide);

  // Class 0 as background, listed among the present classes as datasets with a background class
  // do: its CAM is not used, its seeds are where every present CAM is weak.
  const cv::Mat with = SeedsFromCams(cams, {0, 2}, 0, options);
  int background_in_disc = 0;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      background_in_disc += with.at<uchar>(y, x) == 0 && InsideDisc(x, y, 0.0f);
    }
  }
  EXPECT_GT(CountLabel(with, 0), kSide * kSide / 4);
  EXPECT_EQ(background_in_disc, 0);
  EXPECT_EQ(CountLabel(with, 2), CountLabel(without, 2));
  EXPECT_EQ(CountLabel(with, 3), 0);

  const cv::Mat refined = RefineWithSuperpixels(with, DiscImage(), options);
  EXPECT_GT(CountLabel(refined, 0), kSide * kSide / 4);
  EXPECT_EQ(CountLabel(refined, 3), 0);
}

TEST(Cues, OnlyBackgroundWhenNoForegroundClassIsPresent) {
  const cv::Mat seeds = SeedsFromCams(Cams(), {0}, 0, CueOptions());
  EXPECT_EQ(CountLabel(seeds, 0), kSide * kSide);
}

TEST(Cues, ArgmaxAmongPresentClasses) {
  // Two overlapping classes: each pixel goes to the larger normalized CAM.
  const int sizes[] = {3, 1, 4};
  cv::Mat cams(3, sizes, CV_32F, cv::Scalar(0));
  const float a[] = {1.0f, 0.9f, 0.2f, 0.0f};  // max 1
  const float b[] = {0.0f, 1.0f, 1.6f, 2.0f};  // max 2: normalized 0, 0.5, 0.8, 1
  for (int x = 0; x < 4; ++x) {
    cams.at<float>(0, 0, x) = a[x];
    cams.at<float>(1, 0, x) = b[x];
    cams.at<float>(2, 0, x) = 100.0f;  // not present
  }
  const cv::Mat seeds = SeedsFromCams(cams, {0, 1}, -1, CueOptions());
  EXPECT_EQ(seeds.at<uchar>(0, 0), 0);
  EXPECT_EQ(seeds.at<uchar>(0, 1), 0);  // 0.9 vs 0.5
  EXPECT_EQ(seeds.at<uchar>(0, 2), 1);  // 0.2 vs 0.8
  EXPECT_EQ(seeds.at<uchar>(0, 3), 1);
}

TEST(Cues, FusionKeepsAgreementAndOneSidedCuesAndDropsConflicts) {
  const cv::Mat colour = (cv::Mat_<uchar>(1, 5) << 1, 1, kUnknown, 2, kUnknown);
  const cv::Mat grey = (cv::Mat_<uchar>(1, 5) << 1, 3, 4, kUnknown, kUnknown);
  const cv::Mat fused = FuseCues(colour, grey);
  const cv::Mat expected = (cv::Mat_<uchar>(1, 5) << 1, kUnknown, 4, 2, kUnknown);
  EXPECT_EQ(cv::countNonZero(fused != expected), 0);
  EXPECT_THROW(FuseCues(colour, cv::Mat(2, 5, CV_8UC1)), InputError);
  // Agreed labels only: the one-sided labels 4 and 2 are dropped as well.
  const cv::Mat agreed = FuseCues(colour, grey, /*one_sided=*/false);
  const cv::Mat expected_agreed =
      (cv::Mat_<uchar>(1, 5) << 1, kUnknown, kUnknown, kUnknown, kUnknown);
  EXPECT_EQ(cv::countNonZero(agreed != expected_agreed), 0);
}

// A segmenter's blurry disc: its probability falls off 8 px beyond the disc's edge, as bilinearly
// upsampled stride-16 logits do. Classes: 0 the disc's, 1 absent from the image-level labels (the
// network's favourite in the bottom-left corner), 2 background.
cv::Mat BlurryDiscProbabilities() {
  const int sizes[] = {3, kSide, kSide};
  cv::Mat probabilities(3, sizes, CV_32F);
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const float d = std::hypot(x - kCentre.x, y - kCentre.y) - kRadius;
      // Disc probability 0.9 inside, 0.85 up to 8 px outside, then 0.1.
      float p0 = d <= 0.0f ? 0.9f : (d <= 8.0f ? 0.85f : 0.1f);
      float p1 = 0.0f;
      if (y >= 110 && x < 40) {
        p1 = 0.8f;
        p0 = 0.05f;
      }
      probabilities.at<float>(0, y, x) = p0;
      probabilities.at<float>(1, y, x) = p1;
      probabilities.at<float>(2, y, x) = 1.0f - p0 - p1;
    }
  }
  return probabilities;
}

struct DiscCount {
  int spill = 0, spill_pixels = 0;    // disc cues 2-8 px outside the disc
  int inside = 0, inside_pixels = 0;  // disc cues more than 2 px inside
  int ring_background = 0;            // background cues 2-8 px outside
};

DiscCount CountDiscCues(const cv::Mat& cues) {
  DiscCount n;
  for (int y = 0; y < kSide; ++y) {
    for (int x = 0; x < kSide; ++x) {
      const int c = cues.at<uchar>(y, x);
      EXPECT_NE(c, 1) << "absent class at " << x << "," << y;
      const float d = std::hypot(x - kCentre.x, y - kCentre.y) - kRadius;
      if (d > 2.0f && d <= 8.0f) {
        ++n.spill_pixels;
        n.spill += c == 0;
        n.ring_background += c == 2;
      } else if (d < -2.0f) {
        ++n.inside_pixels;
        n.inside += c == 0;
      }
    }
  }
  return n;
}

// The self-training round's cues: the blurry disc, a class the image-level labels do not list,
// and a flat region where the network is undecided.
TEST(Cues, SegmentationCuesFollowTheImageAndTheImageLevelLabels) {
  const cv::Mat image = DiscImage();
  const cv::Mat probabilities = BlurryDiscProbabilities();
  semantic::DenseCrfOptions crf_options;
  crf_options.num_threads = 1;
  semantic::DenseCrf crf(crf_options);
  const cv::Mat cues = CuesFromSegmentation(probabilities, {0}, 2, image, cv::Mat(), crf, 0.8f);
  ASSERT_EQ(cues.size(), image.size());
  const DiscCount n = CountDiscCues(cues);
  // The network's confident spill ring (0.85 for the disc) does not become disc cues: the CRF
  // follows the colour edge. Inside, the disc is seeded.
  EXPECT_LT(n.spill, n.spill_pixels / 20) << n.spill << " of " << n.spill_pixels;
  EXPECT_GT(n.inside, n.inside_pixels * 9 / 10) << n.inside << " of " << n.inside_pixels;
  // Where the absent class was favoured, the background takes over.
  EXPECT_EQ(cues.at<uchar>(120, 20), 2);
  // A higher confidence keeps a strict subset of the seeds, with the same labels.
  const cv::Mat strict = CuesFromSegmentation(probabilities, {0}, 2, image, cv::Mat(), crf, 1.0f);
  const int kept = cv::countNonZero(strict != kUnknown);
  EXPECT_LT(kept, cv::countNonZero(cues != kUnknown));
  EXPECT_EQ(cv::countNonZero((strict != kUnknown) & (strict != cues)), 0);
  EXPECT_THROW(CuesFromSegmentation(probabilities, {3}, 2, image, cv::Mat(), crf, 0.8f),
               InputError);
  EXPECT_THROW(CuesFromSegmentation(probabilities, {0}, 2, image, cv::Mat(), crf, 0.0f),
               InputError);
}

// With depth (an RGB-D training set), the CRF's depth kernel finds the edge colour does not
// show: a disc 2 m in front of the wall, both the same grey.
TEST(Cues, SegmentationCuesFollowDepthWhereColourHasNoEdge) {
  const cv::Mat image(kSide, kSide, CV_8UC3, cv::Scalar(120, 120, 120));
  cv::Mat depth(kSide, kSide, CV_32FC1, cv::Scalar(3.0f));
  cv::circle(depth, kCentre, static_cast<int>(kRadius), cv::Scalar(1.0f), cv::FILLED);
  depth(cv::Rect(0, 0, 8, 8)).setTo(0.0f);  // holes take no part in the depth kernel
  const cv::Mat probabilities = BlurryDiscProbabilities();
  semantic::DenseCrfOptions colour_options;
  colour_options.num_threads = 1;
  semantic::DenseCrf colour_crf(colour_options);
  const DiscCount colour = CountDiscCues(
      CuesFromSegmentation(probabilities, {0}, 2, image, cv::Mat(), colour_crf, 0.8f));
  // Colour alone has no edge to hold the disc: the wide appearance kernel (80 px) spreads the
  // background over it.
  EXPECT_LT(colour.inside, colour.inside_pixels / 10)
      << colour.inside << " of " << colour.inside_pixels;
  semantic::DenseCrfOptions depth_options = colour_options;
  depth_options.depth = true;
  semantic::DenseCrf depth_crf(depth_options);
  const DiscCount with_depth =
      CountDiscCues(CuesFromSegmentation(probabilities, {0}, 2, image, depth, depth_crf, 0.8f));
  EXPECT_LT(with_depth.spill, with_depth.spill_pixels / 20)
      << with_depth.spill << " of " << with_depth.spill_pixels;
  EXPECT_GT(with_depth.inside, with_depth.inside_pixels * 9 / 10);
  EXPECT_GT(with_depth.ring_background, with_depth.spill_pixels / 2);
  // The depth kernel needs the depth.
  EXPECT_THROW(CuesFromSegmentation(probabilities, {0}, 2, image, cv::Mat(), depth_crf, 0.8f),
               InputError);
}

TEST(Cues, OptionsCheckNamesTheField) {
  CueOptions options;
  EXPECT_NO_THROW(options.Check());
  options.min_coverage = 0.0f;
  try {
    options.Check();
    FAIL() << "no exception";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("min_coverage"), std::string::npos) << e.what();
  }
  options = CueOptions();
  options.superpixel_size = 1;
  EXPECT_THROW(options.Check(), InputError);
  EXPECT_THROW(SeedsFromCams(Cams(), {7}, -1, CueOptions()), InputError);
  EXPECT_THROW(SeedsFromCams(cv::Mat(4, 4, CV_32F), {0}, -1, CueOptions()), InputError);
}

TEST(Cues, RenderingsHaveTheImageSize) {
  const cv::Mat image = DiscImage();
  const cv::Mat seeds = SeedsFromCams(Cams(), {2}, 0, CueOptions());
  const cv::Mat cue = RenderCue(seeds, image);
  ASSERT_EQ(cue.type(), CV_8UC3);
  ASSERT_EQ(cue.size(), image.size());
  // Different classes render differently at pixels of equal image colour.
  cv::Mat grey(4, 4, CV_8UC1, cv::Scalar(100));
  cv::Mat labels = (cv::Mat_<uchar>(4, 4) << 0, 1, kUnknown, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0);
  const cv::Mat small = RenderCue(labels, grey);
  EXPECT_NE(small.at<cv::Vec3b>(0, 0), small.at<cv::Vec3b>(0, 1));
  EXPECT_NE(small.at<cv::Vec3b>(0, 0), small.at<cv::Vec3b>(0, 2));

  const cv::Mat cams = Cams();
  const cv::Mat plane(kSide, kSide, CV_32F, const_cast<uchar*>(cams.ptr(2)));
  const cv::Mat heat = RenderCam(plane, image);
  ASSERT_EQ(heat.type(), CV_8UC3);
  ASSERT_EQ(heat.size(), image.size());
  // JET: the peak is red-ish, the far corner blue-ish.
  const cv::Vec3b peak = heat.at<cv::Vec3b>(64, 63);
  const cv::Vec3b corner = heat.at<cv::Vec3b>(127, 0);
  EXPECT_GT(int(peak[2]) - int(peak[0]), int(corner[2]) - int(corner[0]));
}

}  // namespace
TEST(CuesTest, CellLabelsSuppressAbsentClassesPerCell) {
  // Two classes, CAMs 1 everywhere, a 2x2 grid on a 6x4 map: class 0 listed in the top-left cell
  // only, class 1 in every cell but the bottom-right one.
  const int sizes[] = {2, 4, 6};
  cv::Mat cams(3, sizes, CV_32F, cv::Scalar(1.0f));
  SuppressAbsentInCells(cams, {{0, 1}, {1}, {1}, {}}, 2, 2);
  const cv::Mat c0(4, 6, CV_32F, cams.ptr(0));
  const cv::Mat c1(4, 6, CV_32F, cams.ptr(1));
  EXPECT_EQ(cv::countNonZero(c0), 6);
  EXPECT_EQ(cv::countNonZero(c0(cv::Rect(0, 0, 3, 2))), 6);
  EXPECT_EQ(cv::countNonZero(c1), 18);
  EXPECT_EQ(cv::countNonZero(c1(cv::Rect(3, 2, 3, 2))), 0);
  // So the seeds follow: class 0 wins only in its cell (ties go to the lowest class).
  const cv::Mat seeds = SeedsFromCams(cams, {0, 1}, -1, CueOptions());
  EXPECT_EQ(seeds.at<uint8_t>(0, 0), 0);
  EXPECT_EQ(seeds.at<uint8_t>(0, 5), 1);
  EXPECT_EQ(seeds.at<uint8_t>(3, 5), kUnknown);
  EXPECT_THROW(SuppressAbsentInCells(cams, {{0}}, 2, 2), InputError);
}

TEST(CuesTest, PerCellMaximaGiveEveryListedCellItsOwnPeak) {
  // One class whose CAM is 4 in the left cell and 1 in the right one: normalized over the image,
  // the right cell never reaches a 0.5 threshold; normalized per cell, both cells peak at 1.
  const int sizes[] = {1, 2, 4};
  cv::Mat cams(3, sizes, CV_32F, cv::Scalar(1.0f));
  cv::Mat plane(2, 4, CV_32F, cams.ptr(0));
  plane(cv::Rect(0, 0, 2, 2)).setTo(4.0f);
  cv::Mat image_wide = cams.clone();
  SuppressAbsentInCells(image_wide, {{0}, {0}}, 1, 2);
  EXPECT_EQ(SeedsFromCams(image_wide, {0}, -1, CueOptions()).at<uint8_t>(0, 3), kUnknown);
  SuppressAbsentInCells(cams, {{0}, {0}}, 1, 2, /*per_cell_max=*/true);
  EXPECT_FLOAT_EQ(plane.at<float>(0, 0), 1.0f);
  EXPECT_FLOAT_EQ(plane.at<float>(1, 3), 1.0f);
  EXPECT_EQ(SeedsFromCams(cams, {0}, -1, CueOptions()).at<uint8_t>(0, 3), 0);
}

TEST(CuesTest, ClearLabelInCellsUnseedsOnlyThatLabelInTheFlaggedCells) {
  cv::Mat seeds(4, 4, CV_8UC1, cv::Scalar(2));
  seeds(cv::Rect(0, 0, 1, 4)).setTo(1);
  // 2x2 grid: the top-left and bottom-right cells flagged.
  ClearLabelInCells(seeds, {true, false, false, true}, 2, 2, 2);
  EXPECT_EQ(seeds.at<uint8_t>(0, 0), 1);         // another label stays
  EXPECT_EQ(seeds.at<uint8_t>(0, 1), kUnknown);  // flagged cell
  EXPECT_EQ(seeds.at<uint8_t>(0, 3), 2);         // unflagged cell
  EXPECT_EQ(seeds.at<uint8_t>(3, 1), 2);         // unflagged cell
  EXPECT_EQ(seeds.at<uint8_t>(3, 3), kUnknown);  // flagged cell
  EXPECT_EQ(cv::countNonZero(seeds == kUnknown), 2 + 4);
  EXPECT_THROW(ClearLabelInCells(seeds, {true}, 2, 2, 2), InputError);
}

TEST(CuesTest, MissedClassesAreTheLabelledOnesSeededBelowTheFraction) {
  cv::Mat cue(10, 10, CV_8UC1, cv::Scalar(kUnknown));
  cue(cv::Rect(0, 0, 10, 5)).setTo(3);  // background, 50 %
  cue(cv::Rect(0, 5, 2, 1)).setTo(0);   // class 0 on 2 %
  cue(cv::Rect(0, 6, 1, 1)).setTo(1);   // class 1 on 1 %
  // Class 2 is labelled but never seeded; the background never counts as missed.
  EXPECT_EQ(MissedClasses(cue, {0, 1, 2, 3}, 3, 0.015f), (std::vector<int>{1, 2}));
  EXPECT_EQ(MissedClasses(cue, {0, 1, 3}, 3, 0.01f), std::vector<int>{});
  EXPECT_EQ(MissedClasses(cue, {0, 1, 3}, 3, 0.03f), (std::vector<int>{0, 1}));
}

TEST(CuesTest, FillClassesFromPutsOnlyTheGivenClassesOverTheCue) {
  cv::Mat cue(4, 4, CV_8UC1, cv::Scalar(3));
  cue(cv::Rect(0, 0, 4, 1)).setTo(kUnknown);
  // The source at twice the cue's size: resized by nearest neighbour.
  cv::Mat source(8, 8, CV_8UC1, cv::Scalar(kUnknown));
  source(cv::Rect(0, 0, 4, 4)).setTo(1);  // cue's top-left 2x2
  source(cv::Rect(4, 4, 4, 4)).setTo(2);  // cue's bottom-right 2x2, not asked for
  FillClassesFrom(source, {1}, cue);
  EXPECT_EQ(cue.at<uint8_t>(0, 0), 1);  // over kUnknown
  EXPECT_EQ(cue.at<uint8_t>(1, 1), 1);  // over the background
  EXPECT_EQ(cue.at<uint8_t>(0, 2), kUnknown);
  EXPECT_EQ(cue.at<uint8_t>(3, 3), 3);  // class 2 was not asked for
  EXPECT_EQ(cv::countNonZero(cue == 1), 4);
  cv::Mat wrong(4, 4, CV_32F);
  EXPECT_THROW(FillClassesFrom(wrong, {1}, cue), InputError);
}

}  // namespace moslam::weak
