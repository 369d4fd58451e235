#include "moslam/feature/matcher.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/feature/test_images.h"
#include "moslam/geometry/se3.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

OrbExtractorOptions Options(int n) {
  OrbExtractorOptions o;
  o.num_features = n;
  return o;
}

camera::PinholeCamera Camera() { return test::TestCamera(); }

cv::Mat Warp(const cv::Mat& image, const cv::Mat& affine) {
  cv::Mat out;
  cv::warpAffine(image, out, affine, image.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  return out;
}

cv::Point2f Apply(const cv::Mat& affine, const cv::Point2f& p) {
  return cv::Point2f(static_cast<float>(affine.at<double>(0, 0) * p.x +
                                        affine.at<double>(0, 1) * p.y + affine.at<double>(0, 2)),
                     static_cast<float>(affine.at<double>(1, 0) * p.x +
                                        affine.at<double>(1, 1) * p.y + affine.at<double>(1, 2)));
}

TEST(MatcherTest, DescriptorDistanceCountsBits) {
  uint8_t a[32] = {}, b[32] = {};
  EXPECT_EQ(DescriptorDistance(a, b), 0);
  b[0] = 0xFF;
  b[31] = 0x81;
  b[13] = 0x10;
  EXPECT_EQ(DescriptorDistance(a, b), 11);
  for (uint8_t& x : a) x = 0xFF;
  EXPECT_EQ(DescriptorDistance(a, b), 256 - 11);
}

// The parallel bit count against counting bit by bit, on words with every bit count (0..64 set
// bits at random places) and on random words.
TEST(MatcherTest, PopCountMatchesCountingBitByBit) {
  std::mt19937_64 rng(7);
  const auto slow = [](uint64_t v) {
    int n = 0;
    for (int i = 0; i < 64; ++i) n += static_cast<int>((v >> i) & 1u);
    return n;
  };
  for (int bits = 0; bits <= 64; ++bits) {
    uint64_t v = 0;
    while (slow(v) < bits) v |= uint64_t{1} << (rng() % 64);
    EXPECT_EQ(PopCount64(v), bits) << std::hex << v;
  }
  for (int i = 0; i < 10000; ++i) {
    const uint64_t v = rng();
    ASSERT_EQ(PopCount64(v), slow(v)) << std::hex << v;
  }
  EXPECT_EQ(PopCount64(~uint64_t{0}), 64);
}

TEST(MatcherTest, RotationHistogramKeepsDominantBins) {
  std::vector<float> angles;
  for (int i = 0; i < 100; ++i) angles.push_back(30.0f + static_cast<float>(i % 7) - 3.0f);
  for (int i = 0; i < 20; ++i) angles.push_back(-160.0f);  // 200 deg, 20% of the largest bin
  for (int i = 0; i < 5; ++i) angles.push_back(100.0f);    // 5% of the largest bin
  angles.push_back(359.0f);                                // wraps to bin 0, alone
  const std::vector<bool> keep = RotationConsistent(angles);
  for (int i = 0; i < 120; ++i) EXPECT_TRUE(keep[i]) << i;
  for (int i = 120; i < 126; ++i) EXPECT_FALSE(keep[i]) << i;
  EXPECT_TRUE(RotationConsistent({}).empty());
}

TEST(MatcherTest, RotatedImageMatchesWithHighInlierRate) {
  const cv::Mat image = test::TexturedImage(640, 480, 31);
  const cv::Mat affine = cv::getRotationMatrix2D(cv::Point2f(319.5f, 239.5f), 30.0, 1.0);
  const cv::Mat rotated = Warp(image, affine);
  OrbExtractor e1(Options(1000)), e2(Options(1000));
  const OrbFeatures f1 = e1.Extract(image);
  const OrbFeatures f2 = e2.Extract(rotated);
  auto inliers = [&](const std::vector<DescriptorMatch>& matches) {
    int n = 0;
    for (const DescriptorMatch& m : matches) {
      const cv::KeyPoint& k1 = f1.keypoints[m.index1];
      const cv::Point2f d = Apply(affine, k1.pt) - f2.keypoints[m.index2].pt;
      if (std::hypot(d.x, d.y) < 2.0f * e1.scale_factors()[k1.octave]) ++n;
    }
    return n;
  };
  DescriptorMatchOptions options;
  const auto with =
      MatchByDescriptor(f1.keypoints, f1.descriptors, f2.keypoints, f2.descriptors, options);
  options.check_orientation = false;
  const auto without =
      MatchByDescriptor(f1.keypoints, f1.descriptors, f2.keypoints, f2.descriptors, options);
  RecordProperty("matches", static_cast<int>(with.size()));
  RecordProperty("inliers", inliers(with));
  RecordProperty("matches_without_histogram", static_cast<int>(without.size()));
  ASSERT_GT(with.size(), 200u);
  EXPECT_GT(inliers(with), 0.9 * with.size());
  EXPECT_LE(with.size(), without.size());
  EXPECT_EQ(inliers(with), inliers(without));  // the histogram removes no correct match
  std::vector<bool> used(f2.keypoints.size());
  for (size_t k = 0; k < with.size(); ++k) {
    EXPECT_LE(with[k].distance, kThLow);
    EXPECT_FALSE(used[with[k].index2]);
    used[with[k].index2] = true;
    if (k > 0) {
      EXPECT_LT(with[k - 1].index1, with[k].index1);
    }
  }
}

// A textured plane at depth z seen from two camera positions that differ by a sideways
// translation: the second image is the first shifted by fx * t / z pixels.
TEST(MatcherTest, ProjectionMatcherFindsKeypointsOfKnownPose) {
  const camera::PinholeCamera cam = Camera();
  const double z = 5.0, shift_px = 7.3;
  const geometry::SE3 T_world_cam2(Eigen::Matrix3d::Identity(),
                                   Eigen::Vector3d(shift_px * z / cam.fx(), 0.0, 0.0));
  const cv::Mat image1 = test::TexturedImage(640, 480, 41);
  const cv::Mat affine = (cv::Mat_<double>(2, 3) << 1, 0, -shift_px, 0, 1, 0);
  const cv::Mat image2 = Warp(image1, affine);
  OrbExtractor e1(Options(1000)), e2(Options(1000));
  const Frame frame1 = MakeMonocularFrame(0.0, image1, cv::Mat(), &e1, cam);  // world = camera 1
  const Frame frame2 = MakeMonocularFrame(0.1, image2, cv::Mat(), &e2, cam);

  const geometry::SE3 T_cam2_world = T_world_cam2.Inverse();
  auto project = [&](double offset_px) {
    std::vector<ProjectedPoint> points;
    for (size_t i = 0; i < frame1.size(); ++i) {
      const cv::Point2f& pt = frame1.keypoints_undistorted[i].pt;
      const Eigen::Vector3d p_world = z * cam.UnprojectPinhole(Eigen::Vector2d(pt.x, pt.y));
      const auto px = cam.ProjectPinhole(T_cam2_world * p_world);
      ProjectedPoint p;
      p.pixel =
          Eigen::Vector2f(static_cast<float>(px->x() + offset_px), static_cast<float>(px->y()));
      p.octave = frame1.keypoints[i].octave;
      p.descriptor = frame1.descriptor(i);
      points.push_back(p);
    }
    return points;
  };
  auto count_correct = [&](const std::vector<int>& match, int* matched) {
    int correct = 0;
    *matched = 0;
    for (size_t i = 0; i < match.size(); ++i) {
      if (match[i] < 0) continue;
      ++*matched;
      const cv::Point2f d = Apply(affine, frame1.keypoints[i].pt) - frame2.keypoints[match[i]].pt;
      if (std::hypot(d.x, d.y) < 1.5f * frame1.scale_factors[frame1.keypoints[i].octave]) {
        ++correct;
      }
    }
    return correct;
  };

  ProjectionMatchOptions options;
  options.radius = 3.0f;
  const std::vector<int> match = MatchByProjection(frame2, project(0.0), options);
  ASSERT_EQ(match.size(), frame1.size());
  int matched = 0;
  const int correct = count_correct(match, &matched);
  RecordProperty("projection_matched", matched);
  RecordProperty("projection_correct", correct);
  EXPECT_GT(matched, 0.6 * frame1.size());
  EXPECT_GT(correct, 0.95 * matched);
  std::vector<int> owner(frame2.size(), -1);  // no keypoint matched twice
  for (size_t i = 0; i < match.size(); ++i) {
    if (match[i] < 0) continue;
    EXPECT_EQ(owner[match[i]], -1);
    owner[match[i]] = static_cast<int>(i);
  }

  // A wrong pose (20 px off) must not produce the right keypoints.
  int wrong_matched = 0;
  const int wrong_correct =
      count_correct(MatchByProjection(frame2, project(20.0), options), &wrong_matched);
  EXPECT_LT(wrong_correct, 0.02 * frame1.size());
}

TEST(MatcherTest, FramesMatchByDescriptor) {
  const camera::PinholeCamera cam = Camera();
  const cv::Mat image1 = test::TexturedImage(640, 480, 43);
  const cv::Mat affine = (cv::Mat_<double>(2, 3) << 1, 0, 4.6, 0, 1, -3.2);
  OrbExtractor e1(Options(800)), e2(Options(800));
  const Frame f1 = MakeMonocularFrame(0.0, image1, cv::Mat(), &e1, cam);
  const Frame f2 = MakeMonocularFrame(0.1, Warp(image1, affine), cv::Mat(), &e2, cam);
  const std::vector<DescriptorMatch> matches = MatchByDescriptor(f1, f2);
  int correct = 0;
  for (const DescriptorMatch& m : matches) {
    const cv::Point2f d =
        Apply(affine, f1.keypoints[m.index1].pt) - f2.keypoints_undistorted[m.index2].pt;
    if (std::hypot(d.x, d.y) < 1.5f * f1.scale_factors[f1.keypoints[m.index1].octave]) ++correct;
  }
  EXPECT_GT(matches.size(), 0.3 * f1.size());
  EXPECT_GT(correct, 0.95 * matches.size());
}

TEST(MatcherTest, OptionsAreChecked) {
  DescriptorMatchOptions d;
  d.ratio = 0.0f;
  EXPECT_THROW(d.Check(), InputError);
  ProjectionMatchOptions p;
  p.max_distance = -1;
  EXPECT_THROW(p.Check(), InputError);
  p = ProjectionMatchOptions();
  p.radius = 0.0f;
  EXPECT_THROW(p.Check(), InputError);
}

}  // namespace
}  // namespace moslam::feature
