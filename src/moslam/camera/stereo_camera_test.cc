#include "moslam/camera/stereo_camera.h"

#include <limits>

#include <gtest/gtest.h>

#include "moslam/util/error.h"

namespace moslam::camera {
namespace {

PinholeOptions KittiLeft() {
  PinholeOptions o;
  o.fx = o.fy = 707.0912;
  o.cx = 601.8873;
  o.cy = 183.1104;
  o.width = 1226;
  o.height = 370;
  return o;
}

TEST(StereoCamera, BaselineFromBfOfKitti) {
  // ORB-SLAM2's KITTI04-12 settings: Camera.bf = 379.8145, fx = 707.0912 -> 0.537 m.
  EXPECT_NEAR(BaselineFromBf(379.8145, 707.0912), 0.53715, 1e-5);
  const StereoCamera stereo(KittiLeft(), 379.8145);
  EXPECT_DOUBLE_EQ(stereo.baseline(), 379.8145 / 707.0912);
  EXPECT_DOUBLE_EQ(stereo.bf(), 379.8145);
  EXPECT_DOUBLE_EQ(stereo.left().fx(), 707.0912);
}

TEST(StereoCamera, RejectsInvalidBf) {
  EXPECT_THROW(BaselineFromBf(0.0, 700.0), InputError);
  EXPECT_THROW(BaselineFromBf(-40.0, 700.0), InputError);
  EXPECT_THROW(BaselineFromBf(std::numeric_limits<double>::quiet_NaN(), 700.0), InputError);
  EXPECT_THROW(BaselineFromBf(40.0, 0.0), InputError);
  EXPECT_THROW(StereoCamera(KittiLeft(), -1.0), InputError);
  PinholeOptions bad = KittiLeft();
  bad.fx = -1.0;
  EXPECT_THROW(StereoCamera(bad, 379.8145), InputError);
}

TEST(StereoCamera, DepthAndDisparityAreInverse) {
  const StereoCamera stereo(KittiLeft(), 379.8145);
  EXPECT_DOUBLE_EQ(stereo.DisparityFromDepth(10.0), 37.98145);
  EXPECT_NEAR(*stereo.DepthFromDisparity(stereo.DisparityFromDepth(7.5)), 7.5, 1e-12);
  EXPECT_FALSE(stereo.DepthFromDisparity(0.0).has_value());
  EXPECT_FALSE(stereo.DepthFromDisparity(-3.0).has_value());
}

TEST(StereoCamera, RightProjectionIsShiftedByTheDisparityOnTheSameRow) {
  const StereoCamera stereo(KittiLeft(), 379.8145);
  const Eigen::Vector3d p(1.5, -0.4, 12.0);
  const Eigen::Vector2d left = *stereo.left().ProjectPinhole(p);
  const Eigen::Vector2d right = *stereo.ProjectRight(p);
  EXPECT_DOUBLE_EQ(right.y(), left.y());
  EXPECT_NEAR(left.x() - right.x(), stereo.DisparityFromDepth(12.0), 1e-12);
  // The right camera is the left one moved by +baseline along x.
  const Eigen::Vector3d p_right = p - Eigen::Vector3d(stereo.baseline(), 0.0, 0.0);
  EXPECT_LT((*stereo.left().ProjectPinhole(p_right) - right).norm(), 1e-9);
  EXPECT_FALSE(stereo.ProjectRight({0.0, 0.0, -1.0}).has_value());
}

}  // namespace
}  // namespace moslam::camera
