// Two-view monocular initialization on synthetic correspondences with pixel noise and 20 %
// outliers: model selection (planar scene -> homography, general scene -> fundamental), the
// recovered motion against the ground truth, and degenerate inputs reported as results.
#include "moslam/slam/mono_initializer.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

struct Scene {
  std::vector<Eigen::Vector2d> p1, p2;
  std::vector<bool> outlier;
};

Eigen::Matrix3d TestK() {
  Eigen::Matrix3d K;
  K << 700, 0, 640, 0, 700, 240, 0, 0, 1;
  return K;
}

// Camera 2 relative to camera 1: 4 degrees about a tilted axis, 0.5 m mostly sideways.
geometry::SE3 TrueMotion(double baseline = 0.5) {
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(4.0 * M_PI / 180.0, Eigen::Vector3d(0.2, 1.0, 0.1).normalized())
          .toRotationMatrix();
  return geometry::SE3(R, baseline * Eigen::Vector3d(1.0, 0.1, 0.2).normalized());
}

// `planar`: points on a ground plane 1.5 m below camera 1, 3-27 m ahead (a homography's twofold
// ambiguity is resolved by cheirality there: a fronto-parallel patch would leave two valid
// motions and, as in ORB-SLAM2, no clear winner); else in a box 4-12 m deep.
Scene MakeScene(bool planar, const geometry::SE3& T_2_1, int n = 400, double outliers = 0.2,
                double noise_px = 0.7, uint32_t seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> ux(-4.0, 4.0), uy(-2.0, 2.0), uz(4.0, 12.0);
  std::uniform_real_distribution<double> upx(0.0, 1280.0), upy(0.0, 480.0), u01(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, noise_px);
  const Eigen::Matrix3d K = TestK();
  Scene s;
  while (static_cast<int>(s.p1.size()) < n) {
    Eigen::Vector3d X(ux(rng), uy(rng), uz(rng));
    if (planar) X = Eigen::Vector3d(3.0 * ux(rng), 1.5, 3.0 * uz(rng) - 9.0);
    const Eigen::Vector3d X2 = T_2_1 * X;
    if (X2.z() <= 0.1) continue;
    Eigen::Vector2d a = (K * X).hnormalized() + Eigen::Vector2d(noise(rng), noise(rng));
    Eigen::Vector2d b = (K * X2).hnormalized() + Eigen::Vector2d(noise(rng), noise(rng));
    const bool out = u01(rng) < outliers;
    if (out) b = Eigen::Vector2d(upx(rng), upy(rng));
    s.p1.push_back(a);
    s.p2.push_back(b);
    s.outlier.push_back(out);
  }
  return s;
}

double RotationErrorDeg(const geometry::SE3& a, const geometry::SE3& b) {
  return a.rotation().angularDistance(b.rotation()) * 180.0 / M_PI;
}

double DirectionErrorDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0)) * 180.0 / M_PI;
}

void ExpectMotion(const MonoInitialization& r, const geometry::SE3& truth) {
  EXPECT_LT(RotationErrorDeg(r.T_cam2_cam1, truth), 0.5);
  EXPECT_LT(DirectionErrorDeg(r.T_cam2_cam1.translation(), truth.translation()), 5.0);
  EXPECT_NEAR(r.T_cam2_cam1.translation().norm(), 1.0, 1e-9);
}

TEST(MonoInitializer, PlanarSceneSelectsHomographyAndRecoversMotion) {
  const geometry::SE3 truth = TrueMotion();
  const Scene s = MakeScene(true, truth);
  const MonoInitialization r = InitializeTwoView(s.p1, s.p2, TestK());
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.model, TwoViewModel::kHomography) << "R_H " << r.ratio_h;
  EXPECT_GT(r.ratio_h, 0.40);
  ExpectMotion(r, truth);
  EXPECT_GE(r.parallax_deg, 1.0);
  // Most inlier correspondences triangulated, no outlier among them beyond the chance that a
  // random pixel lands within a few pixels of the transfer.
  int good = 0, bad = 0;
  for (size_t i = 0; i < s.p1.size(); ++i) {
    if (!r.triangulated[i]) continue;
    (s.outlier[i] ? bad : good) += 1;
  }
  EXPECT_GT(good, 250);
  EXPECT_LT(bad, 5);
  EXPECT_EQ(r.num_triangulated, good + bad);
}

TEST(MonoInitializer, GeneralSceneSelectsFundamentalAndRecoversMotion) {
  const geometry::SE3 truth = TrueMotion();
  const Scene s = MakeScene(false, truth);
  const MonoInitialization r = InitializeTwoView(s.p1, s.p2, TestK());
  ASSERT_TRUE(r.ok) << r.reason;
  EXPECT_EQ(r.model, TwoViewModel::kFundamental) << "R_H " << r.ratio_h;
  EXPECT_LE(r.ratio_h, 0.40);
  ExpectMotion(r, truth);
  // Triangulated points match the true structure up to the unknown scale (|t| = 0.5 m -> 1).
  int checked = 0;
  for (size_t i = 0; i < s.p1.size(); ++i) {
    if (!r.triangulated[i] || s.outlier[i]) continue;
    const Eigen::Vector3d X = r.points_cam1[i] * 0.5;
    EXPECT_GT(X.z(), 3.0);
    EXPECT_LT(X.z(), 13.0);
    ++checked;
  }
  EXPECT_GT(checked, 250);
}

TEST(MonoInitializer, SameSeedSameResult) {
  const Scene s = MakeScene(false, TrueMotion());
  const MonoInitialization a = InitializeTwoView(s.p1, s.p2, TestK());
  MonoInitializerOptions parallel;
  parallel.parallel = true;
  const MonoInitialization b = InitializeTwoView(s.p1, s.p2, TestK(), parallel);
  ASSERT_TRUE(a.ok && b.ok);
  EXPECT_EQ(a.score_h, b.score_h);
  EXPECT_EQ(a.score_f, b.score_f);
  EXPECT_EQ(a.T_cam2_cam1.Matrix(), b.T_cam2_cam1.Matrix());
  EXPECT_EQ(a.triangulated, b.triangulated);
}

TEST(MonoInitializer, PureRotationIsNotInitialized) {
  const geometry::SE3 rotation_only(TrueMotion().rotation_matrix(), Eigen::Vector3d::Zero());
  for (bool planar : {false, true}) {
    const Scene s = MakeScene(planar, rotation_only);
    const MonoInitialization r = InitializeTwoView(s.p1, s.p2, TestK());
    EXPECT_FALSE(r.ok) << "planar " << planar;
    EXPECT_FALSE(r.reason.empty());
    // A rotation is a homography of any scene.
    EXPECT_EQ(r.model, TwoViewModel::kHomography) << "R_H " << r.ratio_h;
  }
}

TEST(MonoInitializer, TooFewMatchesIsNotInitialized) {
  const Scene s = MakeScene(false, TrueMotion(), 7, 0.0);
  const MonoInitialization r = InitializeTwoView(s.p1, s.p2, TestK());
  EXPECT_FALSE(r.ok);
  EXPECT_FALSE(r.reason.empty());
  // Enough for RANSAC but fewer than min_triangulated points.
  const Scene s40 = MakeScene(false, TrueMotion(), 40, 0.0);
  const MonoInitialization r40 = InitializeTwoView(s40.p1, s40.p2, TestK());
  EXPECT_FALSE(r40.ok);
  EXPECT_FALSE(r40.reason.empty());
}

TEST(MonoInitializer, RejectsBadOptions) {
  MonoInitializerOptions o;
  o.ransac_iterations = 0;
  const Scene s = MakeScene(false, TrueMotion(), 20, 0.0);
  EXPECT_THROW(InitializeTwoView(s.p1, s.p2, TestK(), o), InputError);
}

}  // namespace
}  // namespace moslam::slam
