// Fusion of duplicated map points between two keyframes.
#include "moslam/slam/fuse.h"

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"

namespace moslam::slam {
namespace {

TEST(Fuse, DuplicatesAreMergedAndMissingObservationsAdded) {
  const testing::Scene scene = testing::RandomScene(60, 7);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  auto kf2 = testing::ObserveScene(&map, scene, testing::CameraAt(0.3));
  // Points 0-39 mapped from kf1 only; points 20-39 mapped again, separately, from kf2.
  testing::AddSharedPoints(&map, scene, {kf1}, 0, 40);
  testing::AddSharedPoints(&map, scene, {kf2}, 20, 40);
  ASSERT_EQ(map.points().size(), 60u);
  std::vector<std::shared_ptr<map::MapPoint>> from_kf1(kf1->points.begin(),
                                                       kf1->points.begin() + 40);
  const int fused = Fuse(&map, kf2, from_kf1, testing::TestCamera());
  EXPECT_GE(fused, 36);
  EXPECT_LE(map.points().size(), 44u);  // at most 4 of the 20 duplicates left
  int shared = 0;
  for (int i = 0; i < 40; ++i) {
    if (kf1->points[i] && kf1->points[i] == kf2->points[i]) ++shared;
  }
  EXPECT_GE(shared, 36);
  for (const auto& [id, p] : map.points()) EXPECT_FALSE(p->bad);
}

TEST(Fuse, WrongDescriptorIsNotFused) {
  const testing::Scene scene = testing::RandomScene(30, 8);
  testing::Scene other = scene;
  other.descriptors = cv::Mat();  // the copy shares scene's pixels until reassigned
  cv::bitwise_not(scene.descriptors, other.descriptors);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  auto kf2 = testing::ObserveScene(&map, other, testing::CameraAt(0.3));
  testing::AddSharedPoints(&map, scene, {kf1}, 0, 30);
  EXPECT_EQ(Fuse(&map, kf2, kf1->points, testing::TestCamera()), 0);
}

TEST(SearchInNeighbors, MergesDuplicatesOfCovisibleKeyframes) {
  const testing::Scene scene = testing::RandomScene(80, 9);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  auto kf2 = testing::ObserveScene(&map, scene, testing::CameraAt(0.3));
  testing::AddSharedPoints(&map, scene, {kf1, kf2}, 0, 30);  // covisible
  testing::AddSharedPoints(&map, scene, {kf1}, 30, 60);
  testing::AddSharedPoints(&map, scene, {kf2}, 30, 60);  // duplicates
  kf1->UpdateConnections();
  kf2->UpdateConnections();
  SearchInNeighbors(&map, kf2, testing::TestCamera());
  EXPECT_LE(map.points().size(), 30u + 33u);
  EXPECT_GE(kf2->Weight(kf1->id), 57);
}

}  // namespace
}  // namespace moslam::slam
