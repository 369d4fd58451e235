#include "moslam/camera/pinhole_camera.h"
#include "moslam/testing/error_of.h"

#include <functional>
#include <limits>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/camera/camera_check.h"
#include "moslam/util/error.h"

namespace moslam::camera {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

PinholeOptions EurocCam0() {
  PinholeOptions o;
  o.fx = 458.654;
  o.fy = 457.296;
  o.cx = 367.215;
  o.cy = 248.375;
  o.width = 752;
  o.height = 480;
  o.distortion = {-0.28340811, 0.07395907, 0.00019359, 1.76187114e-05, 0.0};
  return o;
}

PinholeOptions Ideal() {
  PinholeOptions o;
  o.fx = 500.0;
  o.fy = 400.0;
  o.cx = 320.0;
  o.cy = 240.0;
  o.width = 640;
  o.height = 480;
  return o;
}

using ::moslam::testing::ErrorOf;

TEST(PinholeOptions, ValidOptionsPass) {
  EXPECT_NO_THROW(EurocCam0().Check());
  PinholeOptions unknown_size = Ideal();
  unknown_size.width = unknown_size.height = 0;
  unknown_size.cx = 5000.0;  // cannot be checked without a size
  EXPECT_NO_THROW(unknown_size.Check());
}

TEST(PinholeOptions, InvalidValuesNameTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<std::pair<std::string, std::function<void(PinholeOptions*)>>> cases = {
      {"fx", [](PinholeOptions* o) { o->fx = 0.0; }},
      {"fx", [](PinholeOptions* o) { o->fx = -500.0; }},
      {"fy", [nan](PinholeOptions* o) { o->fy = nan; }},
      {"cx", [](PinholeOptions* o) { o->cx = std::numeric_limits<double>::infinity(); }},
      {"cx", [](PinholeOptions* o) { o->cx = 640.0; }},
      {"cy", [](PinholeOptions* o) { o->cy = -1.0; }},
      {"width", [](PinholeOptions* o) { o->width = -1; }},
      {"width", [](PinholeOptions* o) { o->height = 0; }},
      {"k1", [nan](PinholeOptions* o) { o->distortion.k1 = nan; }},
  };
  for (const auto& [field, edit] : cases) {
    PinholeOptions o = Ideal();
    edit(&o);
    EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr(field));
    EXPECT_THROW(PinholeCamera{o}, InputError) << field;
  }
}

// Issue 31: focal lengths far outside what a lens of this image size can have overflowed poses
// further on; they are refused with the field named.
TEST(PinholeOptions, FocalLengthsOutsideTheSaneRangeNameTheField) {
  for (const double f : {1e-300, 0.5, 1e300, 1e7}) {
    PinholeOptions o = Ideal();
    o.fx = f;
    EXPECT_THAT(ErrorOf([&] { o.Check(); }), AllOf(HasSubstr("camera fx"), HasSubstr("focal")))
        << f;
    o = Ideal();
    o.fy = f;
    EXPECT_THAT(ErrorOf([&] { CheckPinholeOptions(o, "Camera."); }), HasSubstr("Camera.fy")) << f;
  }
  // The range's ends for a 640x480 image: 6.4 and 640000 px.
  PinholeOptions o = Ideal();
  o.fx = 6.4;
  EXPECT_NO_THROW(o.Check());
  o.fx = 640000.0;
  EXPECT_NO_THROW(o.Check());
  // Without an image size, the absolute range.
  o.width = o.height = 0;
  o.fx = 1e300;
  EXPECT_THAT(ErrorOf([&] { o.Check(); }), HasSubstr("fx"));
}

TEST(PinholeOptions, DistortionMustBeInvertibleOverTheImage) {
  struct Case {
    const char* name;
    Distortion d;
  };
  const std::vector<Case> cases = {
      {"k1 = -1e6", {-1e6, 0, 0, 0, 0}},
      {"k3 = 1e300", {0, 0, 0, 0, 1e300}},
      {"p1 = 0.9", {0, 0, 0.9, 0, 0}},
      {"k1 = -1 (folds inside the image)", {-1.0, 0, 0, 0, 0}},
  };
  for (const Case& c : cases) {
    PinholeOptions o = EurocCam0();
    o.distortion = c.d;
    EXPECT_THAT(ErrorOf([&] { CheckPinholeOptions(o, "Camera."); }),
                AllOf(HasSubstr("Camera.k1"), HasSubstr("Camera.p1"), HasSubstr("752x480")))
        << c.name;
    EXPECT_THROW(PinholeCamera{o}, InputError) << c.name;
  }
  // Real calibrations pass: EuRoC's cam0 and ORB-SLAM2's TUM1 (freiburg1) coefficients.
  EXPECT_NO_THROW(EurocCam0().Check());
  PinholeOptions tum1 = Ideal();
  tum1.fx = 517.306408;
  tum1.fy = 516.469215;
  tum1.cx = 318.643040;
  tum1.cy = 255.313989;
  tum1.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  EXPECT_NO_THROW(tum1.Check());
  // Without an image size there is nothing to check the distortion over.
  PinholeOptions unknown = EurocCam0();
  unknown.width = unknown.height = 0;
  unknown.distortion.k1 = -1e6;
  EXPECT_NO_THROW(unknown.Check());
}

TEST(PinholeCamera, CalibrationMatrix) {
  const PinholeCamera camera(Ideal());
  Eigen::Matrix3d k;
  k << 500, 0, 320, 0, 400, 240, 0, 0, 1;
  EXPECT_EQ(camera.K(), k);
  EXPECT_FALSE(camera.HasDistortion());
  EXPECT_TRUE(PinholeCamera(EurocCam0()).HasDistortion());
}

TEST(PinholeCamera, ProjectsAKnownPoint) {
  const PinholeCamera camera(Ideal());
  const auto px = camera.Project({1.0, -2.0, 4.0});
  ASSERT_TRUE(px.has_value());
  EXPECT_DOUBLE_EQ(px->x(), 500.0 * 0.25 + 320.0);
  EXPECT_DOUBLE_EQ(px->y(), 400.0 * -0.5 + 240.0);
  EXPECT_EQ(*camera.ProjectPinhole({1.0, -2.0, 4.0}), *px);  // no distortion: the same
}

TEST(PinholeCamera, PointsNotInFrontHaveNoProjection) {
  const PinholeCamera camera(EurocCam0());
  EXPECT_FALSE(camera.Project({0.1, 0.1, 0.0}).has_value());
  EXPECT_FALSE(camera.Project({0.1, 0.1, -1.0}).has_value());
  EXPECT_FALSE(camera.ProjectPinhole({0.1, 0.1, -1.0}).has_value());
  EXPECT_FALSE(camera.Project({std::numeric_limits<double>::quiet_NaN(), 0.0, 1.0}).has_value());
  EXPECT_TRUE(camera.Project({0.1, 0.1, 1e-3}).has_value());
}

TEST(PinholeCamera, DistortionMovesProjectionsAwayFromPinhole) {
  const PinholeCamera camera(EurocCam0());
  const Eigen::Vector3d p(0.5, 0.4, 1.0);
  const Eigen::Vector2d distorted = *camera.Project(p);
  const Eigen::Vector2d ideal = *camera.ProjectPinhole(p);
  EXPECT_GT((distorted - ideal).norm(), 10.0);  // barrel distortion pulls points inwards
  EXPECT_LT((distorted - Eigen::Vector2d(camera.cx(), camera.cy())).norm(),
            (ideal - Eigen::Vector2d(camera.cx(), camera.cy())).norm());
  EXPECT_LT((camera.DistortPixel(ideal) - distorted).norm(), 1e-9);
  EXPECT_LT((camera.UndistortPixel(distorted) - ideal).norm(), 1e-7);
}

TEST(PinholeCamera, ProjectUnprojectRoundTrip) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> lateral(-0.6, 0.6);
  std::uniform_real_distribution<double> depth(0.5, 20.0);
  for (const PinholeOptions& options : {Ideal(), EurocCam0()}) {
    const PinholeCamera camera(options);
    for (int i = 0; i < 200; ++i) {
      const double z = depth(rng);
      const Eigen::Vector3d p(lateral(rng) * z, lateral(rng) * z * 0.7, z);
      const auto px = camera.Project(p);
      ASSERT_TRUE(px.has_value());
      const Eigen::Vector3d ray = camera.Unproject(*px);
      EXPECT_DOUBLE_EQ(ray.z(), 1.0);
      EXPECT_LT((ray * z - p).norm(), 1e-9 * z);
      const Eigen::Vector3d bearing = camera.Bearing(*px);
      EXPECT_NEAR(bearing.norm(), 1.0, 1e-12);
      EXPECT_LT((bearing - p.normalized()).norm(), 1e-10);
      // The pinhole pair ignores distortion on both sides.
      const Eigen::Vector3d pinhole_ray = camera.UnprojectPinhole(*camera.ProjectPinhole(p));
      EXPECT_LT((pinhole_ray * z - p).norm(), 1e-9 * z);
    }
  }
}

TEST(PinholeCamera, PixelNormalizedConversions) {
  const PinholeCamera camera(Ideal());
  const Eigen::Vector2d px(100.0, 50.0);
  const Eigen::Vector2d n = camera.PixelToNormalized(px);
  EXPECT_DOUBLE_EQ(n.x(), (100.0 - 320.0) / 500.0);
  EXPECT_DOUBLE_EQ(n.y(), (50.0 - 240.0) / 400.0);
  EXPECT_LT((camera.NormalizedToPixel(n) - px).norm(), 1e-12);
  EXPECT_EQ(camera.UndistortPixel(px), camera.NormalizedToPixel(n));
}

TEST(PinholeCamera, InImageHonoursTheBorder) {
  const PinholeCamera camera(Ideal());
  EXPECT_TRUE(camera.InImage({0.0, 0.0}));
  EXPECT_TRUE(camera.InImage({639.9, 479.9}));
  EXPECT_FALSE(camera.InImage({640.0, 10.0}));
  EXPECT_FALSE(camera.InImage({-0.1, 10.0}));
  EXPECT_FALSE(camera.InImage({5.0, 10.0}, 8.0));
  EXPECT_TRUE(camera.InImage({8.0, 10.0}, 8.0));
  EXPECT_FALSE(camera.InImage({10.0, 472.5}, 8.0));
}

}  // namespace
}  // namespace moslam::camera
