#include "moslam/feature/frame.h"

#include <cmath>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/feature/test_images.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

camera::PinholeOptions Vga(bool distorted) {
  camera::PinholeOptions o;
  o.fx = 517.3;
  o.fy = 516.5;
  o.cx = 318.6;
  o.cy = 255.3;
  o.width = 640;
  o.height = 480;
  if (distorted) {  // TUM fr1's calibration
    o.distortion.k1 = 0.2624;
    o.distortion.k2 = -0.9531;
    o.distortion.p1 = -0.0054;
    o.distortion.p2 = 0.0026;
    o.distortion.k3 = 1.1633;
  }
  return o;
}

OrbExtractorOptions Options(int n) {
  OrbExtractorOptions o;
  o.num_features = n;
  return o;
}

TEST(FrameTest, MonocularFrameFillsEverything) {
  const cv::Mat image = test::TexturedImage(640, 480, 3);
  OrbExtractor extractor(Options(1000));
  const camera::PinholeCamera cam(Vga(false));
  const Frame f = MakeMonocularFrame(1.5, image, cv::Mat(), &extractor, cam);
  EXPECT_EQ(f.timestamp, 1.5);
  ASSERT_EQ(f.size(), 1000u);
  EXPECT_EQ(f.descriptors.rows, 1000);
  EXPECT_EQ(f.keypoints_undistorted.size(), 1000u);
  EXPECT_EQ(f.NumWithDepth(), 0);
  EXPECT_EQ(f.num_levels(), 8);
  EXPECT_FLOAT_EQ(f.scale_factors[1], 1.2f);
  EXPECT_FLOAT_EQ(f.level_sigma2[2], 1.44f * 1.44f);
  EXPECT_EQ(f.bf, 0.0);
  for (size_t i = 0; i < f.size(); ++i) {
    EXPECT_EQ(f.keypoints[i].pt, f.keypoints_undistorted[i].pt);  // no distortion
    EXPECT_EQ(f.u_right[i], -1.0f);
  }
  // Every keypoint is found by a search around itself.
  for (size_t i = 0; i < f.size(); ++i) {
    const auto& pt = f.keypoints_undistorted[i].pt;
    EXPECT_THAT(f.FeaturesInArea(pt.x, pt.y, 0.5f), ::testing::Contains(i));
  }
}

TEST(FrameTest, MaskGoesToExtractor) {
  const cv::Mat image = test::TexturedImage(640, 480, 4);
  const cv::Mat mask = test::MovableMask(image.size(), 0.3, 5);
  OrbExtractor extractor(Options(1000));
  const Frame f =
      MakeMonocularFrame(0.0, image, mask, &extractor, camera::PinholeCamera(Vga(false)));
  for (const cv::KeyPoint& kp : f.keypoints) {
    EXPECT_EQ(mask.at<uint8_t>(static_cast<int>(std::lround(kp.pt.y)),
                               static_cast<int>(std::lround(kp.pt.x))),
              0);
  }
}

TEST(FrameTest, DistortedCameraUndistortsKeypointsAndBounds) {
  const cv::Mat image = test::TexturedImage(640, 480, 6);
  OrbExtractor extractor(Options(500));
  const camera::PinholeCamera cam(Vga(true));
  const Frame f = MakeMonocularFrame(0.0, image, cv::Mat(), &extractor, cam);
  const ImageBounds b = f.bounds;
  EXPECT_NE(b.min_x, 0.0f);
  EXPECT_LT(b.min_x, b.max_x);
  for (size_t i = 0; i < f.size(); ++i) {
    const auto& raw = f.keypoints[i].pt;
    const auto& und = f.keypoints_undistorted[i].pt;
    const Eigen::Vector2d back = cam.DistortPixel(Eigen::Vector2d(und.x, und.y));
    EXPECT_NEAR(back.x(), raw.x, 1e-2);
    EXPECT_NEAR(back.y(), raw.y, 1e-2);
    EXPECT_EQ(f.keypoints[i].octave, f.keypoints_undistorted[i].octave);
  }
}

TEST(FrameTest, RgbdDepthAndVirtualRightCoordinate) {
  const cv::Mat image = test::TexturedImage(640, 480, 8);
  // Depth varies over the image; the left quarter has no measurement.
  cv::Mat depth(image.size(), CV_32FC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      depth.at<float>(r, c) = c < 160 ? 0.0f : 1.0f + 0.01f * c + 0.002f * r;
    }
  }
  OrbExtractor extractor(Options(1000));
  const camera::PinholeCamera cam(Vga(false));
  const double bf = 40.0;
  const Frame f = MakeRgbdFrame(2.0, image, depth, cv::Mat(), &extractor, cam, bf);
  EXPECT_EQ(f.bf, bf);
  int with = 0, without = 0;
  for (size_t i = 0; i < f.size(); ++i) {
    const cv::Point2f& pt = f.keypoints[i].pt;
    const int c = static_cast<int>(std::lround(pt.x)), r = static_cast<int>(std::lround(pt.y));
    if (c < 160) {
      EXPECT_EQ(f.depth[i], -1.0f);
      EXPECT_EQ(f.u_right[i], -1.0f);
      EXPECT_FALSE(f.UnprojectCamera(i, cam).has_value());
      ++without;
    } else {
      const float d = 1.0f + 0.01f * c + 0.002f * r;
      EXPECT_FLOAT_EQ(f.depth[i], d);
      EXPECT_NEAR(f.u_right[i], pt.x - bf / d, 1e-4);
      const auto p = f.UnprojectCamera(i, cam);
      ASSERT_TRUE(p.has_value());
      EXPECT_NEAR(p->z(), d, 1e-5);
      EXPECT_NEAR(cam.ProjectPinhole(*p)->x(), pt.x, 1e-3);
      ++with;
    }
  }
  EXPECT_EQ(f.NumWithDepth(), with);
  EXPECT_GT(with, 500);
  EXPECT_GT(without, 50);
}

TEST(FrameTest, RgbdRejectsWrongDepthImage) {
  const cv::Mat image = test::TexturedImage(640, 480, 8);
  OrbExtractor extractor(Options(200));
  const camera::PinholeCamera cam(Vga(false));
  const cv::Mat depth16(image.size(), CV_16UC1, cv::Scalar(1000));
  EXPECT_THROW(MakeRgbdFrame(0.0, image, depth16, cv::Mat(), &extractor, cam, 40.0), InputError);
  const cv::Mat small(240, 320, CV_32FC1, cv::Scalar(1.0f));
  EXPECT_THROW(MakeRgbdFrame(0.0, image, small, cv::Mat(), &extractor, cam, 40.0), InputError);
}

}  // namespace
}  // namespace moslam::feature
