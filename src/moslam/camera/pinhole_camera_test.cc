#include "moslam/camera/pinhole_camera.h"
#include "moslam/testing/error_of.h"

#include <functional>
#include <limits>
#include <random>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/util/error.h"

namespace moslam::camera {
namespace {

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
