#include "moslam/feature/stereo_matcher.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/frame.h"
#include "moslam/feature/test_images.h"
#include "moslam/io/image.h"
#include "moslam/io/kitti.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

OrbExtractorOptions Options(int n) {
  OrbExtractorOptions o;
  o.num_features = n;
  return o;
}

// A right image whose content is the left image moved left by `disparity` pixels, i.e. a
// fronto-parallel scene at depth bf / disparity.
cv::Mat ShiftLeft(const cv::Mat& image, double disparity) {
  const cv::Mat m = (cv::Mat_<double>(2, 3) << 1, 0, -disparity, 0, 1, 0);
  cv::Mat out;
  cv::warpAffine(image, out, m, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

camera::StereoCamera SyntheticCamera(double bf) {
  camera::PinholeOptions o;
  o.fx = o.fy = 700.0;
  o.cx = 600.0;
  o.cy = 185.0;
  o.width = 1226;
  o.height = 370;
  return camera::StereoCamera(o, bf);
}

// The SAD refinement runs on the keypoint's pyramid level, so its sub-pixel accuracy is in pixels
// of that level: 0.5 px there is 0.5 * scale px at level 0 (up to 1.8 px on level 7). Keypoints
// of levels 0 and 1 must reach 0.5 px at level 0. The texture is blurred a little like a real
// lens; without that the aliasing of the pyramid's resizing dominates the error. Disparities are
// fractional: an integer shift makes most SADs zero, and the median-based outlier rejection then
// discards many exact matches.
TEST(StereoMatcherTest, SyntheticShiftGivesKnownDepth) {
  cv::Mat left = test::TexturedImage(1226, 370, 21);
  cv::GaussianBlur(left, left, cv::Size(0, 0), 1.5);
  for (const double d : {12.4, 31.7}) {
    const cv::Mat right = ShiftLeft(left, d);
    const camera::StereoCamera cam = SyntheticCamera(380.0);
    OrbExtractor le(Options(2000)), re(Options(2000));
    const Frame f = MakeStereoFrame(0.0, left, right, cv::Mat(), &le, &re, cam);
    int matched = 0, good_at_level = 0, fine = 0, fine_good = 0, good_level0 = 0;
    for (size_t i = 0; i < f.size(); ++i) {
      if (f.depth[i] <= 0.0f) continue;
      ++matched;
      const double disparity = cam.bf() / f.depth[i];
      EXPECT_NEAR(f.keypoints[i].pt.x - f.u_right[i], disparity, 1e-3);
      const int level = f.keypoints[i].octave;
      const double error = std::abs(disparity - d);
      if (error < 0.5 * f.scale_factors[level]) ++good_at_level;
      if (error < 0.5) ++good_level0;
      if (level <= 1) {
        ++fine;
        if (error < 0.5) ++fine_good;
      }
    }
    RecordProperty("within_half_px_level0_d" + std::to_string(static_cast<int>(d * 10)),
                   std::to_string(static_cast<double>(good_level0) / matched));
    // Keypoints near the right border have no partner in the shifted image.
    EXPECT_GT(matched, 0.55 * f.size()) << "disparity " << d;
    EXPECT_GT(good_at_level, 0.9 * matched) << "disparity " << d;
    EXPECT_GT(fine, 200) << "disparity " << d;
    EXPECT_GT(fine_good, 0.9 * fine) << "disparity " << d;
  }
}

TEST(StereoMatcherTest, MatchStereoReportsRightIndices) {
  const cv::Mat left = test::TexturedImage(800, 400, 22);
  const cv::Mat right = ShiftLeft(left, 20.0);
  OrbExtractor le(Options(1000)), re(Options(1000));
  const OrbFeatures lf = le.Extract(left);
  const OrbFeatures rf = re.Extract(right);
  const StereoMatches m = MatchStereo(lf, le, rf, re, 350.0, 700.0);
  ASSERT_EQ(m.depth.size(), lf.keypoints.size());
  int count = 0;
  for (size_t i = 0; i < m.depth.size(); ++i) {
    if (m.right_index[i] < 0) {
      EXPECT_EQ(m.depth[i], -1.0f);
      continue;
    }
    ++count;
    const cv::KeyPoint& kr = rf.keypoints[m.right_index[i]];
    EXPECT_LE(std::abs(kr.octave - lf.keypoints[i].octave), 1);
    // The SAD search moves the match by at most search_half_width (+1 for the sub-pixel step)
    // level pixels, and the level-0 refinement by at most scale + 2 more (issue 29).
    const float scale = le.scale_factors()[lf.keypoints[i].octave];
    EXPECT_NEAR(kr.pt.x, m.u_right[i], 6.0 * scale + scale + 2.0);
  }
  EXPECT_EQ(count, m.num_matches);
  EXPECT_GT(count, 300);
}

TEST(StereoMatcherTest, OptionsAreChecked) {
  StereoMatchOptions o;
  EXPECT_NO_THROW(o.Check());
  o.patch_half_size = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = StereoMatchOptions();
  o.max_descriptor_distance = 300;
  EXPECT_THROW(o.Check(), InputError);
  o = StereoMatchOptions();
  o.min_depth_baselines = 0.0;
  EXPECT_THROW(o.Check(), InputError);
}

TEST(StereoMatcherTest, KittiFrameIsPlausible) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  const io::Sequence seq = io::ReadKitti(folder);
  ASSERT_TRUE(seq.calibration.has_value());
  ASSERT_EQ(seq.sensor, io::SensorType::kStereo);
  const io::FrameImages images = io::LoadFrameImages(seq.frames[0], io::ColourMode::kGrey);
  const camera::StereoCamera cam(seq.calibration->camera, seq.calibration->bf);
  OrbExtractor le(Options(2000)), re(Options(2000));
  const OrbFeatures lf = le.Extract(images.left);
  const OrbFeatures rf = re.Extract(images.right);
  const StereoMatches m = MatchStereo(lf, le, rf, re, cam.bf(), cam.left().fx());
  std::vector<float> row_diff;
  int plausible = 0;
  for (size_t i = 0; i < lf.keypoints.size(); ++i) {
    if (m.right_index[i] < 0) continue;
    row_diff.push_back(std::abs(lf.keypoints[i].pt.y - rf.keypoints[m.right_index[i]].pt.y));
    if (m.depth[i] >= 2.0f && m.depth[i] <= 80.0f) ++plausible;
  }
  const int n = static_cast<int>(row_diff.size());
  RecordProperty("stereo_matches", n);
  // ORB-SLAM2's descriptor threshold of 75 keeps about 40% of 2000 keypoints on KITTI.
  EXPECT_GT(n, 0.35 * lf.keypoints.size());
  EXPECT_GT(plausible, 0.85 * n);
  std::nth_element(row_diff.begin(), row_diff.begin() + n / 2, row_diff.end());
  EXPECT_LT(row_diff[n / 2], 1.0f);
}

}  // namespace
}  // namespace moslam::feature
