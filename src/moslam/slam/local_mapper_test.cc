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

}  // namespace
}  // namespace moslam::slam
