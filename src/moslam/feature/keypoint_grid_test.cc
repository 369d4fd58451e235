#include "moslam/feature/keypoint_grid.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

namespace moslam::feature {
namespace {

std::vector<cv::KeyPoint> RandomKeypoints(int n, const ImageBounds& b, float margin, int seed) {
  cv::RNG rng(seed);
  std::vector<cv::KeyPoint> kps(n);
  for (cv::KeyPoint& kp : kps) {
    kp.pt = cv::Point2f(rng.uniform(b.min_x - margin, b.max_x + margin),
                        rng.uniform(b.min_y - margin, b.max_y + margin));
    kp.octave = rng.uniform(0, 8);
  }
  return kps;
}

std::vector<size_t> BruteForce(const std::vector<cv::KeyPoint>& kps, float x, float y, float r,
                               int min_level, int max_level) {
  std::vector<size_t> out;
  for (size_t i = 0; i < kps.size(); ++i) {
    if (min_level > 0 && kps[i].octave < min_level) continue;
    if (max_level >= 0 && kps[i].octave > max_level) continue;
    if (std::abs(kps[i].pt.x - x) <= r && std::abs(kps[i].pt.y - y) <= r) out.push_back(i);
  }
  return out;
}

TEST(KeypointGridTest, AreaSearchEqualsBruteForce) {
  const ImageBounds bounds{-12.5f, 1250.0f, 3.0f, 380.0f};
  // Some keypoints lie outside the bounds (as undistorted keypoints can).
  const std::vector<cv::KeyPoint> kps = RandomKeypoints(3000, bounds, 15.0f, 7);
  const KeypointGrid grid(bounds, kps);
  cv::RNG rng(11);
  int total = 0;
  for (int q = 0; q < 2000; ++q) {
    const float x = rng.uniform(bounds.min_x - 40.0f, bounds.max_x + 40.0f);
    const float y = rng.uniform(bounds.min_y - 40.0f, bounds.max_y + 40.0f);
    const float r = rng.uniform(0.5f, 120.0f);
    const int min_level = rng.uniform(-1, 4);
    const int max_level = rng.uniform(-1, 8);
    std::vector<size_t> got = grid.FeaturesInArea(kps, x, y, r, min_level, max_level);
    std::sort(got.begin(), got.end());
    const std::vector<size_t> expected = BruteForce(kps, x, y, r, min_level, max_level);
    ASSERT_EQ(got, expected) << "query " << x << "," << y << " r " << r;
    total += static_cast<int>(got.size());
  }
  EXPECT_GT(total, 10000);  // the queries were not trivially empty
}

TEST(KeypointGridTest, ExactCellBoundariesAndLevels) {
  const ImageBounds bounds{0.0f, 640.0f, 0.0f, 480.0f};
  std::vector<cv::KeyPoint> kps;
  // Points exactly on cell borders (cells are 10 x 10 here) and on the image border.
  for (float x : {0.0f, 10.0f, 20.0f, 639.99f, 640.0f}) {
    for (float y : {0.0f, 10.0f, 479.99f, 480.0f}) {
      kps.emplace_back(cv::Point2f(x, y), 31.0f, -1.0f, 0.0f, static_cast<int>(x) % 3);
    }
  }
  const KeypointGrid grid(bounds, kps);
  for (const cv::KeyPoint& kp : kps) {
    const auto got = grid.FeaturesInArea(kps, kp.pt.x, kp.pt.y, 0.0f);
    EXPECT_EQ(got.size(), 1u) << kp.pt;
  }
  EXPECT_EQ(grid.FeaturesInArea(kps, 10.0f, 5.0f, 5.0f).size(), 2u);
  EXPECT_EQ(grid.FeaturesInArea(kps, 10.0f, 5.0f, 5.0f, 2, 2).size(), 0u);  // octave 10 % 3 = 1
  EXPECT_EQ(grid.FeaturesInArea(kps, 10.0f, 5.0f, 5.0f, 1, 1).size(), 2u);
  EXPECT_TRUE(grid.FeaturesInArea(kps, 300.0f, 200.0f, 50.0f).empty());
}

TEST(KeypointGridTest, EmptyGridFindsNothing) {
  const KeypointGrid grid;
  EXPECT_TRUE(grid.FeaturesInArea({}, 1.0f, 1.0f, 10.0f).empty());
}

}  // namespace
}  // namespace moslam::feature
