#include "moslam/slam/loop_correction.h"

#include <gtest/gtest.h>

#include "moslam/slam/camera_model.h"
#include "moslam/slam/test_scene.h"

namespace moslam::slam {
namespace {

optim::CameraModel Model() { return CameraModelFor(testing::TestCamera()); }

// The result a solver would return: every pose moved by `shift` (world x), points unchanged.
optim::BundleResult Shifted(const GlobalBundleJob& job, double shift) {
  optim::BundleResult r;
  for (const auto& T : job.problem.T_cam_world) {
    r.T_cam_world.push_back(
        T * geometry::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-shift, 0.0, 0.0)));
  }
  r.points_world = job.problem.points_world;
  r.edge_inlier.assign(job.problem.edges.size(), true);
  return r;
}

TEST(GlobalBundleMerge, DroppedWhenTheMapWasCorrectedMeanwhile) {
  map::Map map;
  const testing::Scene s = testing::RandomScene(60, 1);
  auto a = testing::ObserveScene(&map, s, testing::CameraAt(0.0));
  auto b = testing::ObserveScene(&map, s, testing::CameraAt(0.5));
  testing::AddSharedPoints(&map, s, {a, b}, 0, 60);
  b->UpdateConnections();
  const GlobalBundleJob job = PrepareGlobalBundleAdjustment(map, Model());
  EXPECT_EQ(job.keyframe_ids.size(), 2u);
  EXPECT_EQ(job.point_ids.size(), 60u);
  EXPECT_TRUE(job.problem.pose_fixed[0]);
  map.BumpGeneration();  // a loop correction while the adjustment ran
  const geometry::SE3 before = b->T_cam_world();
  EXPECT_FALSE(MergeGlobalBundleAdjustment(&map, job, Shifted(job, 0.2)));
  EXPECT_EQ(b->T_cam_world().Matrix(), before.Matrix());
}

TEST(GlobalBundleMerge, KeyframesAddedMeanwhileFollowTheirParent) {
  map::Map map;
  const testing::Scene s = testing::RandomScene(60, 2);
  auto a = testing::ObserveScene(&map, s, testing::CameraAt(0.0));
  auto b = testing::ObserveScene(&map, s, testing::CameraAt(0.5));
  testing::AddSharedPoints(&map, s, {a, b}, 0, 40);
  b->UpdateConnections();
  const GlobalBundleJob job = PrepareGlobalBundleAdjustment(map, Model());
  // A keyframe mapped while the adjustment ran, with a point only it sees.
  auto c = testing::ObserveScene(&map, s, testing::CameraAt(1.0));
  for (int i = 0; i < 40; ++i) {
    c->points[i] = b->points[i];
    b->points[i]->AddObservation(c, i);
  }
  testing::AddSharedPoints(&map, s, {c}, 40, 41);
  c->UpdateConnections();
  const auto parent = c->parent();
  ASSERT_TRUE(parent == a || parent == b);
  const geometry::SE3 T_c_p = c->T_cam_world() * parent->T_world_cam();
  const Eigen::Vector3d own_point = c->points[40]->position;
  const uint64_t generation = map.generation();
  ASSERT_TRUE(MergeGlobalBundleAdjustment(&map, job, Shifted(job, 0.2)));
  EXPECT_EQ(map.generation(), generation + 1);
  EXPECT_NEAR((b->CameraCenter() - Eigen::Vector3d(0.7, 0, 0)).norm(), 0.0, 1e-12);
  // c kept its pose relative to its spanning-tree parent, and its own point moved with it.
  const geometry::SE3 T_c_p_after = c->T_cam_world() * parent->T_world_cam();
  EXPECT_NEAR((T_c_p_after.Matrix() - T_c_p.Matrix()).norm(), 0.0, 1e-12);
  EXPECT_NEAR((c->points[40]->position - own_point - Eigen::Vector3d(0.2, 0, 0)).norm(), 0.0,
              1e-12);
}

}  // namespace
}  // namespace moslam::slam
