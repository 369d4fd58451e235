// Redundant keyframe culling (ORB-SLAM2's 90 % / three-observer rule).
#include "moslam/slam/keyframe_culling.h"

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"

namespace moslam::slam {
namespace {

TEST(KeyFrameCulling, ErasesKeyframesWhosePointsOthersSee) {
  const testing::Scene scene = testing::RandomScene(40, 11);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  std::vector<std::shared_ptr<map::KeyFrame>> kfs;
  for (int k = 0; k < 5; ++k) {
    kfs.push_back(testing::ObserveScene(&map, scene, testing::CameraAt(0.1 * k)));
  }
  testing::AddSharedPoints(&map, scene, kfs, 0, 40);  // every point seen by all five
  for (const auto& kf : kfs) kf->UpdateConnections();
  ASSERT_TRUE(IsRedundant(*kfs[1], map, 0.0));
  // kf1 and kf2 go (ids ascending among equal weights); then kf3's points are seen by only two
  // others (kf0, kf4), so it stays; kf0 is never erased.
  EXPECT_EQ(CullRedundantKeyFrames(&map, kfs[4], 0.0), 2);
  EXPECT_TRUE(kfs[1]->bad());
  EXPECT_TRUE(kfs[2]->bad());
  EXPECT_FALSE(kfs[3]->bad());
  EXPECT_FALSE(kfs[0]->bad());
  EXPECT_EQ(map.keyframes().size(), 3u);
  EXPECT_EQ(map.points().size(), 40u);
  EXPECT_EQ(kfs[3]->parent(), kfs[0]);  // reconnected in the spanning tree
}

TEST(KeyFrameCulling, KeyframeSeenByFewOthersStays) {
  const testing::Scene scene = testing::RandomScene(40, 12);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  std::vector<std::shared_ptr<map::KeyFrame>> kfs;
  for (int k = 0; k < 3; ++k) {
    kfs.push_back(testing::ObserveScene(&map, scene, testing::CameraAt(0.1 * k)));
  }
  testing::AddSharedPoints(&map, scene, kfs, 0, 40);
  for (const auto& kf : kfs) kf->UpdateConnections();
  EXPECT_FALSE(IsRedundant(*kfs[1], map, 0.0));
  EXPECT_EQ(CullRedundantKeyFrames(&map, kfs[2], 0.0), 0);
}

}  // namespace
}  // namespace moslam::slam
