#include "moslam/feature/orb_extractor.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/test_images.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

using ::testing::HasSubstr;

const char kKittiFrame[] = "data/kitti/06_000000-000050/image_0/000000.png";

OrbFeatures ExtractWith(const cv::Mat& image, const cv::Mat& mask, int num_features,
                        int dilation = 0) {
  OrbExtractorOptions options;
  options.num_features = num_features;
  options.mask_dilation_px = dilation;
  OrbExtractor extractor(options);
  return extractor.Extract(image, mask);
}

// Keypoints whose level-0 position rounds to a non-zero mask pixel.
int CountOnMask(const OrbFeatures& features, const cv::Mat& mask) {
  int count = 0;
  for (const cv::KeyPoint& kp : features.keypoints) {
    const int col = std::min(static_cast<int>(std::lround(kp.pt.x)), mask.cols - 1);
    const int row = std::min(static_cast<int>(std::lround(kp.pt.y)), mask.rows - 1);
    if (mask.at<uint8_t>(row, col) != 0) ++count;
  }
  return count;
}

bool Identical(const OrbFeatures& a, const OrbFeatures& b) {
  if (a.keypoints.size() != b.keypoints.size()) return false;
  for (size_t i = 0; i < a.keypoints.size(); ++i) {
    const cv::KeyPoint& p = a.keypoints[i];
    const cv::KeyPoint& q = b.keypoints[i];
    if (p.pt != q.pt || p.angle != q.angle || p.octave != q.octave || p.size != q.size ||
        p.response != q.response) {
      return false;
    }
  }
  return a.descriptors.size() == b.descriptors.size() &&
         (a.descriptors.empty() || cv::norm(a.descriptors, b.descriptors, cv::NORM_INF) == 0);
}

int Hamming(const cv::Mat& a, int i, const cv::Mat& b, int j) {
  int bits = 0;
  const uint8_t* p = a.ptr<uint8_t>(i);
  const uint8_t* q = b.ptr<uint8_t>(j);
  for (int k = 0; k < kOrbDescriptorBytes; ++k) bits += std::bitset<8>(p[k] ^ q[k]).count();
  return bits;
}

// Brute-force Hamming matching with cross-check: pairs (i, j) that are each other's nearest.
std::vector<std::pair<int, int>> CrossCheckedMatches(const cv::Mat& a, const cv::Mat& b) {
  std::vector<int> best_ab(a.rows, -1), best_ba(b.rows, -1);
  std::vector<int> dist_ab(a.rows, 1 << 30), dist_ba(b.rows, 1 << 30);
  for (int i = 0; i < a.rows; ++i) {
    for (int j = 0; j < b.rows; ++j) {
      const int d = Hamming(a, i, b, j);
      if (d < dist_ab[i]) dist_ab[i] = d, best_ab[i] = j;
      if (d < dist_ba[j]) dist_ba[j] = d, best_ba[j] = i;
    }
  }
  std::vector<std::pair<int, int>> matches;
  for (int i = 0; i < a.rows; ++i) {
    if (best_ab[i] >= 0 && best_ba[best_ab[i]] == i && dist_ab[i] <= 64) {
      matches.push_back({i, best_ab[i]});
    }
  }
  return matches;
}

cv::Point2f Apply(const cv::Mat& affine, const cv::Point2f& p) {
  return {static_cast<float>(affine.at<double>(0, 0) * p.x + affine.at<double>(0, 1) * p.y +
                             affine.at<double>(0, 2)),
          static_cast<float>(affine.at<double>(1, 0) * p.x + affine.at<double>(1, 1) * p.y +
                             affine.at<double>(1, 2))};
}

double AngleDifference(double a, double b) {
  const double d = std::fmod(std::fabs(a - b), 360.0);
  return std::min(d, 360.0 - d);
}

TEST(OrbExtractor, ProducesTheBudgetWithConsistentKeypoints) {
  const cv::Mat image = test::TexturedImage(640, 480, 1);
  OrbExtractorOptions options;
  OrbExtractor extractor(options);
  const OrbFeatures features = extractor.Extract(image);
  ASSERT_EQ(features.keypoints.size(), 1000u);
  EXPECT_EQ(features.descriptors.rows, 1000);
  EXPECT_EQ(features.descriptors.cols, 32);
  EXPECT_EQ(features.descriptors.type(), CV_8U);
  std::vector<int> per_level(options.num_levels, 0);
  int previous_octave = 0;
  for (const cv::KeyPoint& kp : features.keypoints) {
    ASSERT_GE(kp.octave, previous_octave) << "keypoints are ordered by level";
    previous_octave = kp.octave;
    ++per_level[kp.octave];
    const float scale = extractor.scale_factors()[kp.octave];
    EXPECT_FLOAT_EQ(kp.size, 31.0f * scale);
    EXPECT_GE(kp.angle, 0.0f);
    EXPECT_LT(kp.angle, 360.0f);
    EXPECT_GT(kp.response, 0.0f);
    // Level coordinates are FAST's integer pixels, at least 19 pixels inside the level image.
    const cv::Mat& level = extractor.level_image(kp.octave);
    const float lx = kp.pt.x * extractor.inv_scale_factors()[kp.octave];
    const float ly = kp.pt.y * extractor.inv_scale_factors()[kp.octave];
    EXPECT_NEAR(lx, std::round(lx), 1e-3);
    EXPECT_NEAR(ly, std::round(ly), 1e-3);
    EXPECT_GE(std::round(lx), kOrbEdgeMargin);
    EXPECT_GE(std::round(ly), kOrbEdgeMargin);
    EXPECT_LT(std::round(lx), level.cols - kOrbEdgeMargin);
    EXPECT_LT(std::round(ly), level.rows - kOrbEdgeMargin);
  }
  // Every level contributes (the texture has corners at every scale).
  for (int l = 0; l < options.num_levels; ++l) EXPECT_GT(per_level[l], 0) << "level " << l;
}

TEST(OrbExtractor, LevelsFollowOrbSlam2) {
  OrbExtractor extractor(OrbExtractorOptions{});
  const std::vector<int>& quota = extractor.features_per_level();
  ASSERT_EQ(quota.size(), 8u);
  EXPECT_EQ(std::accumulate(quota.begin(), quota.end(), 0), 1000);
  // Geometric series with ratio 1/1.2: 1000 (1 - 1/1.2) / (1 - 1.2^-8) = 217.4 at level 0.
  EXPECT_EQ(quota[0], 217);
  for (size_t l = 1; l + 1 < quota.size(); ++l) EXPECT_LT(quota[l], quota[l - 1]);
  EXPECT_NEAR(extractor.scale_factors()[7], std::pow(1.2, 7), 1e-4);
  EXPECT_NEAR(extractor.level_sigma2()[3], std::pow(1.2, 6), 1e-4);
  EXPECT_NEAR(extractor.inv_level_sigma2()[3] * extractor.level_sigma2()[3], 1.0, 1e-6);

  const cv::Mat image = test::TexturedImage(640, 480, 2);
  OrbExtractor e(OrbExtractorOptions{});
  e.Extract(image);
  EXPECT_EQ(e.level_image(0).size(), image.size());
  EXPECT_EQ(e.level_image(1).size(), cv::Size(533, 400));  // round(640 / 1.2), round(480 / 1.2)
}

TEST(OrbExtractor, MaskedExtractionKeepsTheBudgetAndAvoidsTheMask) {
  const cv::Mat image = test::TexturedImage(640, 480, 3);
  const cv::Mat mask = test::MovableMask(image.size(), 0.3, 4);
  ASSERT_GT(cv::countNonZero(mask), 0.25 * image.total());
  const OrbFeatures unmasked = ExtractWith(image, cv::Mat(), 1000);
  const OrbFeatures masked = ExtractWith(image, mask, 1000);
  EXPECT_GT(CountOnMask(unmasked, mask), 100) << "the mask must matter for this test to mean much";
  EXPECT_EQ(masked.keypoints.size(), 1000u);
  EXPECT_EQ(masked.descriptors.rows, 1000);
  EXPECT_EQ(CountOnMask(masked, mask), 0);
  // Coarse levels obey the level-0 mask too.
  int coarse = 0;
  for (const cv::KeyPoint& kp : masked.keypoints) coarse += kp.octave >= 4 ? 1 : 0;
  EXPECT_GT(coarse, 50);
}

// The viewer's "rejected by the mask" keypoints (issue 26): on the mask, about as many as the
// unmasked extractor puts there, and asking for them changes nothing the tracker gets.
TEST(OrbExtractor, KeepMaskedReportsWhatTheMaskTookAndChangesNothingElse) {
  const cv::Mat image = test::TexturedImage(640, 480, 3);
  const cv::Mat mask = test::MovableMask(image.size(), 0.3, 4);
  OrbExtractor plain((OrbExtractorOptions()));
  OrbExtractor watched((OrbExtractorOptions()));
  watched.set_keep_masked(true);
  const OrbFeatures kept = watched.Extract(image, mask);
  EXPECT_TRUE(Identical(plain.Extract(image, mask), kept));
  EXPECT_TRUE(plain.masked_keypoints().empty());
  const std::vector<cv::Point2f>& masked = watched.masked_keypoints();
  const int on_mask = CountOnMask(ExtractWith(image, cv::Mat(), 1000), mask);
  ASSERT_GT(on_mask, 100);
  for (const cv::Point2f& p : masked) {
    ASSERT_NE(mask.at<uint8_t>(std::min(cvRound(p.y), mask.rows - 1),
                               std::min(cvRound(p.x), mask.cols - 1)),
              0)
        << p;
  }
  // Each level's quota is the masked run's, so the count is close to, not equal to, the
  // unmasked extractor's.
  EXPECT_GT(masked.size(), 0.8 * on_mask);
  EXPECT_LT(masked.size(), 1.2 * on_mask);
  std::printf("on the mask: %d keypoints unmasked, %zu reported as masked\n", on_mask,
              masked.size());
  watched.Extract(image);  // no mask: nothing taken
  EXPECT_TRUE(watched.masked_keypoints().empty());
  watched.set_keep_masked(false);
  watched.Extract(image, mask);
  EXPECT_TRUE(watched.masked_keypoints().empty());
}

TEST(OrbExtractor, DilationGrowsTheMask) {
  const cv::Mat image = test::TexturedImage(640, 480, 5);
  const cv::Mat mask = test::MovableMask(image.size(), 0.2, 6);
  const int radius = 9;
  cv::Mat dilated;
  cv::dilate(
      mask, dilated,
      cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * radius + 1, 2 * radius + 1)));
  const cv::Mat ring = dilated & ~mask;
  // Without dilation some keypoints sit in the ring around the mask, with it none do.
  EXPECT_GT(CountOnMask(ExtractWith(image, mask, 1000), ring), 30);
  const OrbFeatures features = ExtractWith(image, mask, 1000, radius);
  EXPECT_EQ(features.keypoints.size(), 1000u);
  EXPECT_EQ(CountOnMask(features, dilated), 0);
}

TEST(OrbExtractor, HalfMaskedImageStillYieldsTheBudget) {
  const cv::Mat image = test::TexturedImage(640, 480, 7);
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8UC1);
  mask(cv::Rect(0, 0, 320, 480)).setTo(1);  // any non-zero value means movable
  const OrbFeatures features = ExtractWith(image, mask, 1000);
  EXPECT_EQ(features.keypoints.size(), 1000u);
  EXPECT_EQ(CountOnMask(features, mask), 0);
  for (const cv::KeyPoint& kp : features.keypoints) ASSERT_GE(kp.pt.x, 319.5f);
}

TEST(OrbExtractor, EmptyMaskAndAllZeroMaskAgree) {
  const cv::Mat image = test::TexturedImage(400, 300, 8);
  EXPECT_TRUE(Identical(ExtractWith(image, cv::Mat(), 500),
                        ExtractWith(image, cv::Mat::zeros(image.size(), CV_8UC1), 500)));
}

TEST(OrbExtractor, IsDeterministicAndReusable) {
  const cv::Mat a = test::TexturedImage(640, 480, 9);
  const cv::Mat b = test::TexturedImage(500, 400, 10);
  const cv::Mat mask = test::MovableMask(a.size(), 0.3, 11);
  OrbExtractorOptions options;
  options.mask_dilation_px = 2;
  OrbExtractor extractor(options);
  const OrbFeatures first = extractor.Extract(a, mask);
  extractor.Extract(b);  // different size: the scratch buffers change in between
  OrbFeatures again;
  extractor.Extract(a, mask, &again);
  EXPECT_TRUE(Identical(first, again));
  OrbExtractor other(options);
  EXPECT_TRUE(Identical(first, other.Extract(a, mask)));
}

TEST(OrbExtractor, MatchesAcrossARotation) {
  // The image and its copy rotated by 30 degrees about the centre: ORB's orientation makes the
  // descriptors match, and the matches must agree with the known rotation.
  const cv::Mat image = test::TexturedImage(640, 640, 12);
  const cv::Mat rotation = cv::getRotationMatrix2D(cv::Point2f(319.5f, 319.5f), 30.0, 1.0);
  cv::Mat rotated;
  cv::warpAffine(image, rotated, rotation, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  const OrbFeatures f1 = ExtractWith(image, cv::Mat(), 1000);
  const OrbFeatures f2 = ExtractWith(rotated, cv::Mat(), 1000);
  const auto matches = CrossCheckedMatches(f1.descriptors, f2.descriptors);
  int inliers = 0;
  for (const auto& [i, j] : matches) {
    const cv::Point2f predicted = Apply(rotation, f1.keypoints[i].pt);
    if (cv::norm(predicted - f2.keypoints[j].pt) < 3.0) ++inliers;
  }
  EXPECT_GT(matches.size(), 200u);
  EXPECT_GT(inliers, 0.7 * static_cast<double>(matches.size()))
      << inliers << " of " << matches.size();
}

TEST(OrbExtractor, DescriptorsAreSteeredByTheOrientation) {
  // The same corner found in both images (same level, position within 1.5 level pixels of the
  // rotated one) has its angle turned by -30 degrees (the rotation is counter-clockwise on
  // screen) and a close descriptor, while unrelated keypoints are ~128 bits apart.
  const cv::Mat image = test::TexturedImage(640, 640, 13);
  const double degrees = 30.0;
  const cv::Mat rotation = cv::getRotationMatrix2D(cv::Point2f(319.5f, 319.5f), degrees, 1.0);
  cv::Mat rotated;
  cv::warpAffine(image, rotated, rotation, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  OrbExtractorOptions options;
  OrbExtractor extractor(options);
  const OrbFeatures f1 = extractor.Extract(image);
  const OrbFeatures f2 = extractor.Extract(rotated);
  std::vector<int> same, random;
  std::vector<double> angle_errors;
  for (size_t i = 0; i < f1.keypoints.size(); ++i) {
    const cv::KeyPoint& kp = f1.keypoints[i];
    const cv::Point2f predicted = Apply(rotation, kp.pt);
    const float tolerance = 1.5f * extractor.scale_factors()[kp.octave];
    for (size_t j = 0; j < f2.keypoints.size(); ++j) {
      const cv::KeyPoint& other = f2.keypoints[j];
      if (other.octave != kp.octave || cv::norm(other.pt - predicted) > tolerance) continue;
      same.push_back(
          Hamming(f1.descriptors, static_cast<int>(i), f2.descriptors, static_cast<int>(j)));
      angle_errors.push_back(AngleDifference(other.angle, kp.angle - degrees));
      random.push_back(Hamming(f1.descriptors, static_cast<int>(i), f2.descriptors,
                               static_cast<int>((j + 97) % f2.keypoints.size())));
      break;
    }
  }
  ASSERT_GT(same.size(), 150u);
  auto median = [](auto values) {
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  };
  EXPECT_LT(median(same), 40);
  EXPECT_GT(median(random), 100);
  EXPECT_LT(median(angle_errors), 5.0);
}

TEST(OrbExtractor, TexturelessImageGivesNoKeypoints) {
  const OrbFeatures features =
      ExtractWith(cv::Mat(200, 200, CV_8UC1, cv::Scalar(128)), cv::Mat(), 500);
  EXPECT_TRUE(features.keypoints.empty());
  EXPECT_EQ(features.descriptors.rows, 0);
  EXPECT_EQ(features.descriptors.cols, 32);
}

TEST(OrbExtractor, SmallImagesWork) {
  const OrbFeatures features = ExtractWith(test::TexturedImage(64, 64, 14), cv::Mat(), 500);
  EXPECT_GT(features.keypoints.size(), 0u);
  EXPECT_LE(features.keypoints.size(), 500u);
  EXPECT_EQ(features.descriptors.rows, static_cast<int>(features.keypoints.size()));
}

TEST(OrbExtractor, ManyLevelsOnASmallImage) {
  // Levels beyond the image's size are skipped; their quota goes to finer levels.
  OrbExtractorOptions options;
  options.num_levels = 20;
  options.scale_factor = 2.0;
  options.num_features = 300;
  OrbExtractor extractor(options);
  const OrbFeatures features = extractor.Extract(test::TexturedImage(320, 240, 16));
  EXPECT_EQ(features.keypoints.size(), 300u);
  EXPECT_TRUE(extractor.level_image(19).empty());
  for (const cv::KeyPoint& kp : features.keypoints) EXPECT_LE(kp.octave, 2);
}

std::string ErrorOf(const cv::Mat& image, const cv::Mat& mask) {
  OrbExtractor extractor(OrbExtractorOptions{});
  try {
    extractor.Extract(image, mask);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "expected InputError";
  return {};
}

TEST(OrbExtractor, RejectsBadImagesAndMasks) {
  const cv::Mat image = test::TexturedImage(320, 240, 15);
  EXPECT_THAT(ErrorOf(cv::Mat(), cv::Mat()), HasSubstr("empty"));
  EXPECT_THAT(ErrorOf(cv::Mat(240, 320, CV_8UC3), cv::Mat()), HasSubstr("CV_8UC1"));
  EXPECT_THAT(ErrorOf(cv::Mat(40, 320, CV_8UC1), cv::Mat()), HasSubstr("smaller"));
  EXPECT_THAT(ErrorOf(image, cv::Mat::zeros(240, 321, CV_8UC1)), HasSubstr("mask is 321x240"));
  EXPECT_THAT(ErrorOf(image, cv::Mat::zeros(240, 320, CV_16UC1)), HasSubstr("mask must be"));
  EXPECT_THAT(ErrorOf(image, cv::Mat::zeros(240, 320, CV_8UC3)), HasSubstr("mask must be"));
  OrbExtractorOptions bad;
  bad.num_levels = 0;
  EXPECT_THROW(OrbExtractor{bad}, InputError);
}

TEST(OrbExtractorKitti, FullBudgetWithAndWithoutACarMask) {
  MOSLAM_SHARED_OR_SKIP(path, kKittiFrame);
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  // The cars of frame 0 (right of the road, parked on the left).
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8UC1);
  cv::rectangle(mask, cv::Rect(710, 165, 135, 92), 255, cv::FILLED);
  cv::rectangle(mask, cv::Rect(643, 172, 45, 30), 255, cv::FILLED);
  cv::rectangle(mask, cv::Rect(278, 186, 50, 26), 255, cv::FILLED);
  const OrbFeatures unmasked = ExtractWith(image, cv::Mat(), 2000);
  const OrbFeatures masked = ExtractWith(image, mask, 2000);
  EXPECT_EQ(unmasked.keypoints.size(), 2000u);
  EXPECT_EQ(masked.keypoints.size(), 2000u);
  EXPECT_GT(CountOnMask(unmasked, mask), 20);
  EXPECT_EQ(CountOnMask(masked, mask), 0);
}

TEST(OrbExtractorKitti, MatchesAcrossARotation) {
  MOSLAM_SHARED_OR_SKIP(path, kKittiFrame);
  const cv::Mat image = cv::imread(path, cv::IMREAD_GRAYSCALE);
  ASSERT_FALSE(image.empty());
  const cv::Point2f centre(image.cols / 2.0f, image.rows / 2.0f);
  const cv::Mat rotation = cv::getRotationMatrix2D(centre, 30.0, 1.0);
  cv::Mat rotated;
  cv::warpAffine(image, rotated, rotation, image.size());
  const OrbFeatures f1 = ExtractWith(image, cv::Mat(), 2000);
  const OrbFeatures f2 = ExtractWith(rotated, cv::Mat(), 2000);
  const auto matches = CrossCheckedMatches(f1.descriptors, f2.descriptors);
  int inliers = 0;
  for (const auto& [i, j] : matches) {
    if (cv::norm(Apply(rotation, f1.keypoints[i].pt) - f2.keypoints[j].pt) < 3.0) ++inliers;
  }
  EXPECT_GT(matches.size(), 150u);
  EXPECT_GT(inliers, 0.7 * static_cast<double>(matches.size()))
      << inliers << " of " << matches.size();
}

}  // namespace
}  // namespace moslam::feature
