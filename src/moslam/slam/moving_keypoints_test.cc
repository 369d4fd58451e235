#include "moslam/slam/moving_keypoints.h"

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::CameraAt;
using testing::ObserveScene;
using testing::TestCamera;

// 30 static points 5-10 m away and 10 points on a body 2 m away (the last 10), observed with
// depth from two cameras 0.05 m apart; between the two frames the body moved `body_shift`.
struct TwoFrames {
  map::Map map;
  feature::Frame earlier, current;
  geometry::SE3 T_earlier_world = CameraAt(0.0), T_current_world = CameraAt(0.05);

  explicit TwoFrames(const Eigen::Vector3d& body_shift) {
    testing::Scene scene = testing::RandomScene(40, 5);
    for (int k = 0; k < 10; ++k) scene.points[30 + k] = {-0.6 + 0.12 * k, 0.1 * (k % 3), 2.0};
    earlier = ObserveScene(&map, scene, T_earlier_world, 40.0)->frame;
    for (int k = 30; k < 40; ++k) scene.points[k] += body_shift;
    current = ObserveScene(&map, scene, T_current_world, 40.0)->frame;
  }
  std::vector<uint8_t> Moving(const MovingKeypointsOptions& options = {}) const {
    return FindMovingKeypoints(current, T_current_world, earlier, T_earlier_world, TestCamera(),
                               options);
  }
};

TEST(MovingKeypoints, FlagsThePointsOfAMovingBodyOnly) {
  // The body walked 0.1 m sideways (25 px at 2 m): its keypoints are found displaced.
  const TwoFrames frames(Eigen::Vector3d(0.1, 0.0, 0.0));
  const std::vector<uint8_t> moving = frames.Moving();
  for (int i = 0; i < 30; ++i) EXPECT_EQ(moving[i], 0) << "static point " << i;
  for (int i = 30; i < 40; ++i) EXPECT_EQ(moving[i], 1) << "body point " << i;
}

TEST(MovingKeypoints, FlagsABodyComingCloserByItsDepth) {
  // Straight towards the camera along the ray of the image centre: the keypoints barely move
  // in the image, their depth changes by 0.3 m.
  const TwoFrames frames(Eigen::Vector3d(0.0, 0.0, -0.3));
  const std::vector<uint8_t> moving = frames.Moving();
  int flagged = 0;
  for (int i = 30; i < 40; ++i) flagged += moving[i];
  for (int i = 0; i < 30; ++i) EXPECT_EQ(moving[i], 0) << "static point " << i;
  EXPECT_EQ(flagged, 10);
}

TEST(MovingKeypoints, AStillSceneAndTheSwitch) {
  const TwoFrames still(Eigen::Vector3d::Zero());
  for (uint8_t m : still.Moving()) EXPECT_EQ(m, 0);
  const TwoFrames frames(Eigen::Vector3d(0.1, 0.0, 0.0));
  MovingKeypointsOptions off;
  off.enabled = false;
  for (uint8_t m : frames.Moving(off)) EXPECT_EQ(m, 0);
  MovingKeypointsOptions bad;
  bad.search_radius = 1.0f;
  EXPECT_THROW(bad.Check(), InputError);
}

}  // namespace
}  // namespace moslam::slam
