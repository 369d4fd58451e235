// Triangulation of new map points between two keyframes with exact synthetic observations.
#include "moslam/slam/new_points.h"

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"

namespace moslam::slam {
namespace {

TEST(CreateNewMapPoints, TriangulatesUnmatchedKeypointsExactly) {
  const testing::Scene scene = testing::RandomScene(120, 3);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  auto kf2 = testing::ObserveScene(&map, scene, testing::CameraAt(1.0));
  // 30 points already mapped make the two keyframes covisible.
  testing::AddSharedPoints(&map, scene, {kf1, kf2}, 0, 30);
  kf1->UpdateConnections();
  kf2->UpdateConnections();
  ASSERT_EQ(kf2->BestCovisibles(-1).size(), 1u);

  const auto created = CreateNewMapPoints(&map, kf2, testing::TestCamera());
  int inside_both = 0;
  for (size_t i = 30; i < scene.points.size(); ++i) {
    const auto& kp1 = kf1->frame.keypoints[i].pt;
    const auto& kp2 = kf2->frame.keypoints[i].pt;
    if (kp1.x >= 0 && kp1.x < 640 && kp1.y >= 0 && kp1.y < 480 && kp2.x >= 0 && kp2.x < 640 &&
        kp2.y >= 0 && kp2.y < 480) {
      ++inside_both;
    }
  }
  EXPECT_GE(static_cast<int>(created.size()), inside_both * 9 / 10);
  for (const auto& p : created) {
    const int i = p->IndexIn(kf2->id);
    ASSERT_GE(i, 30);
    EXPECT_EQ(p->IndexIn(kf1->id), i);  // the right keypoint pair
    EXPECT_LT((p->position - scene.points[i]).norm(), 1e-3 * scene.points[i].z());
    EXPECT_EQ(kf1->points[i], p);
    EXPECT_EQ(p->num_observations(), 2);
    EXPECT_GT(p->max_distance, p->min_distance);
  }
  EXPECT_EQ(map.points().size(), 30u + created.size());
}

TEST(CreateNewMapPoints, NoNeighboursNoPoints) {
  const testing::Scene scene = testing::RandomScene(50, 4);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  EXPECT_TRUE(CreateNewMapPoints(&map, kf, testing::TestCamera()).empty());
}

TEST(SearchForTriangulation, RejectsMatchesOffTheEpipolarLine) {
  const testing::Scene scene = testing::RandomScene(80, 5);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  // kf2 sees the same descriptors 1 m higher up: 50-100 px off the (horizontal) epipolar lines.
  testing::Scene moved = scene;
  for (auto& p : moved.points) p.y() += 1.0;
  auto kf2 = testing::ObserveScene(&map, moved, testing::CameraAt(1.0));
  EXPECT_TRUE(SearchForTriangulation(*kf1, *kf2, testing::TestCamera()).empty());
}

}  // namespace
}  // namespace moslam::slam
