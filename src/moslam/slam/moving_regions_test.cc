#include "moslam/slam/moving_regions.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

// A 640x480 depth image: a wall at 4 m with a box at 2 m over columns 200-320, rows 150-300.
const cv::Rect kBox(200, 150, 121, 151);
cv::Mat Depth() {
  cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(4.0f));
  depth(kBox).setTo(2.0f);
  return depth;
}

// Eight keypoints on the box, two lone ones on the wall far from it.
std::vector<InconsistentKeypoint> Keypoints() {
  std::vector<InconsistentKeypoint> k;
  for (int i = 0; i < 8; ++i) {
    k.push_back({cv::Point2f(205.0f + 13.0f * i, 170.0f + 15.0f * (i % 4)), 2.0f});
  }
  k.push_back({cv::Point2f(560.0f, 60.0f), 4.0f});
  k.push_back({cv::Point2f(50.0f, 420.0f), 4.0f});
  return k;
}

TEST(MovingRegions, AClusterBecomesARegionWithinItsDepthAndLoneKeypointsDoNot) {
  const cv::Mat depth = Depth();
  const cv::Mat mask = MovingRegions(Keypoints(), depth, depth.size(), {});
  ASSERT_FALSE(mask.empty());
  // The cluster's hull is covered ...
  EXPECT_EQ(mask.at<uint8_t>(190, 260), 255);
  EXPECT_EQ(mask.at<uint8_t>(215, 300), 255);
  // ... nothing outside the box: the disc around the keypoint at column 205 would reach column
  // 193 on the wall left of it, which the depth range keeps free.
  cv::Mat outside = mask.clone();
  outside(kBox).setTo(0);
  EXPECT_EQ(cv::countNonZero(outside), 0);
  // The lone keypoints make no region.
  EXPECT_EQ(mask.at<uint8_t>(60, 560), 0);
  EXPECT_EQ(mask.at<uint8_t>(420, 50), 0);
}

TEST(MovingRegions, TooFewKeypointsOrTooFarApartMakeNothing) {
  std::vector<InconsistentKeypoint> k = Keypoints();
  k.resize(4);  // under min_points (5)
  EXPECT_TRUE(MovingRegions(k, Depth(), cv::Size(640, 480), {}).empty());
  // Eight keypoints 100 px apart: no two are linked.
  std::vector<InconsistentKeypoint> spread;
  for (int i = 0; i < 8; ++i) spread.push_back({cv::Point2f(30.0f + 80.0f * i, 240.0f), 2.0f});
  EXPECT_TRUE(MovingRegions(spread, cv::Mat(), cv::Size(640, 480), {}).empty());
}

TEST(MovingRegions, KeypointsAtAnotherDepthDoNotJoinTheCluster) {
  // Five keypoints on the box and five right beside them on the wall, 2 m behind: two clusters of
  // five, each a region of its own depth; with min_points 6 neither is one.
  std::vector<InconsistentKeypoint> k;
  for (int i = 0; i < 5; ++i) k.push_back({cv::Point2f(300.0f, 160.0f + 20.0f * i), 2.0f});
  for (int i = 0; i < 5; ++i) k.push_back({cv::Point2f(330.0f, 160.0f + 20.0f * i), 4.0f});
  MovingRegionOptions options;
  options.min_points = 6;
  EXPECT_TRUE(MovingRegions(k, Depth(), cv::Size(640, 480), options).empty());
  options.min_points = 5;
  EXPECT_FALSE(MovingRegions(k, Depth(), cv::Size(640, 480), options).empty());
}

TEST(MovingRegions, OptionsAreChecked) {
  MovingRegionOptions o;
  o.min_points = 1;
  EXPECT_THROW(o.Check(), InputError);
  o = {};
  o.radius_px = -1;
  EXPECT_THROW(o.Check(), InputError);
  EXPECT_NO_THROW(MovingRegionOptions{}.Check());
}

}  // namespace
}  // namespace moslam::slam
