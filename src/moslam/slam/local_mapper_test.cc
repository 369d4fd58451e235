// Local mapping pieces testable without a whole run: the gauge anchor of local bundle adjustment.
#include "moslam/slam/local_mapper.h"

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"

namespace moslam::slam {
namespace {

std::vector<std::shared_ptr<map::KeyFrame>> MakeKeyFrames(map::Map* map, int n) {
  const testing::Scene scene = testing::RandomScene(10, 21);
  std::vector<std::shared_ptr<map::KeyFrame>> kfs;
  for (int k = 0; k < n; ++k) {
    kfs.push_back(testing::ObserveScene(map, scene, testing::CameraAt(0.1 * k)));
  }
  return kfs;
}

// Keyframe 0 culled or outside the window and no non-local observer: without an anchor the window
// could move rigidly (six free directions the solver only damps). The oldest local keyframe is
// fixed, not the newest (its pose is the least constrained) and not a non-local one.
TEST(AnchorGauge, FixesOldestLocalKeyframeWhenNothingIsFixed) {
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  const auto kfs = MakeKeyFrames(&map, 5);  // ids 0..4
  // Window as LocalBundleAdjustment orders it: the new keyframe first, then its covisibles.
  const std::vector<std::shared_ptr<map::KeyFrame>> poses = {kfs[4], kfs[3], kfs[2], kfs[1]};
  std::vector<bool> fixed(poses.size(), false);
  AnchorGauge(poses, poses.size(), &fixed);
  EXPECT_EQ(fixed, (std::vector<bool>{false, false, false, true}));
}

TEST(AnchorGauge, OnlyLocalPosesAreCandidates) {
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  const auto kfs = MakeKeyFrames(&map, 5);
  // Two local keyframes (4, 2) followed by a non-local one with a smaller id (1) that, for the
  // sake of the test, is not flagged fixed.
  const std::vector<std::shared_ptr<map::KeyFrame>> poses = {kfs[4], kfs[2], kfs[1]};
  std::vector<bool> fixed(poses.size(), false);
  AnchorGauge(poses, 2, &fixed);
  EXPECT_EQ(fixed, (std::vector<bool>{false, true, false}));
}

TEST(AnchorGauge, KeepsAnExistingAnchor) {
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  const auto kfs = MakeKeyFrames(&map, 4);
  const std::vector<std::shared_ptr<map::KeyFrame>> poses = {kfs[3], kfs[2], kfs[1], kfs[0]};
  const std::vector<bool> before = {false, false, false, true};  // a fixed non-local keyframe
  std::vector<bool> fixed = before;
  AnchorGauge(poses, 3, &fixed);
  EXPECT_EQ(fixed, before);
}

// LocalMapperOptions::max_local_keyframes: the adjustment moves the new keyframe and at most that
// many covisible keyframes; the other observers of the local points keep their poses exactly.
// Without the cap every covisible keyframe moves (keyframe 0 anchors the gauge).
TEST(LocalBundleAdjustment, MovesAtMostTheCappedNumberOfCovisibleKeyFrames) {
  for (const int cap : {0, 3}) {
    SCOPED_TRACE(cap);
    map::Map map;
    const testing::Scene scene = testing::RandomScene(60, 5);
    std::vector<std::shared_ptr<map::KeyFrame>> kfs;
    for (int k = 0; k < 8; ++k) {
      kfs.push_back(testing::ObserveScene(&map, scene, testing::CameraAt(0.1 * k), 40.0));
    }
    // Points 0-39 are seen by all, 40-59 by keyframes 4-7 only: keyframes 4-6 are the newest
    // one's best covisibles.
    testing::AddSharedPoints(&map, scene, kfs, 0, 40);
    testing::AddSharedPoints(&map, scene, {kfs.begin() + 4, kfs.end()}, 40, 60);
    std::vector<geometry::SE3> before;
    for (size_t k = 0; k < kfs.size(); ++k) {
      if (k > 0) {  // off by a centimetre or so, so that the adjustment has something to do
        const Eigen::Vector3d shift(0.01 * ((k % 3) - 1.0), 0.008 * ((k % 2) - 0.5), 0.005);
        kfs[k]->SetPose(geometry::SE3(Eigen::Matrix3d::Identity(), shift) * kfs[k]->T_cam_world());
      }
      kfs[k]->UpdateConnections();
      before.push_back(kfs[k]->T_cam_world());
    }
    LocalMapperOptions options;
    options.keyframe_culling = false;  // every keyframe sees every point: all are redundant
    options.max_local_keyframes = cap;
    LocalMapper mapper(&map, testing::TestCamera(), 40.0, options);
    mapper.ProcessKeyFrame(kfs.back());
    ASSERT_EQ(mapper.LocalBundleAdjustments(), 1);
    int moved = 0;
    for (size_t k = 0; k < kfs.size(); ++k) {
      const double change = (kfs[k]->T_cam_world().translation() - before[k].translation()).norm();
      if (change > 1e-9) ++moved;
    }
    EXPECT_EQ(moved, cap == 0 ? 7 : 1 + cap);
    EXPECT_LT((kfs[0]->T_cam_world().translation() - before[0].translation()).norm(), 1e-12);
  }
}

}  // namespace
}  // namespace moslam::slam
