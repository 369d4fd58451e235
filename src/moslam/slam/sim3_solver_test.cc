#include "moslam/slam/sim3_solver.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/so3.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

optim::CameraModel Camera() {
  optim::CameraModel c;
  c.fx = c.fy = 500.0;
  c.cx = 320.0;
  c.cy = 240.0;
  return c;
}

Eigen::Vector2d Project(const optim::CameraModel& c, const Eigen::Vector3d& p) {
  return {c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy};
}

Eigen::Vector3d Unproject(const optim::CameraModel& c, const Eigen::Vector2d& px, double z) {
  return {(px.x() - c.cx) / c.fx * z, (px.y() - c.cy) / c.fy * z, z};
}

struct Scene {
  std::vector<Sim3Correspondence> correspondences;
  std::vector<bool> outlier;
  geometry::Sim3 S_12;  // truth
};

// Points in front of both cameras; camera 2 sees the world at `scale2` times its size (the
// scale drift of a monocular map), so the true S_12 has scale 1 / scale2. Pixels get
// `pixel_noise` (standard deviation), the 3D points a depth-like noise growing with depth; a
// fraction `outliers` of correspondences pair unrelated points.
Scene MakeScene(int n, double scale2, double pixel_noise, double outliers, uint64_t seed) {
  std::mt19937 rng(static_cast<unsigned>(seed));
  std::uniform_real_distribution<double> u(-1.0, 1.0), depth(2.0, 8.0), unit(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  const optim::CameraModel cam = Camera();
  const geometry::SE3 T_c1_w = geometry::SE3::Identity();
  const geometry::SE3 T_c2_w(geometry::ExpSO3(Eigen::Vector3d(0.05, -0.3, 0.02)),
                             Eigen::Vector3d(0.8, 0.1, -0.2));
  Scene s;
  // p2 = scale2 * T_c2_w * X = scale2 * T_c2_w * T_w_c1 * p1.
  s.S_12 = (geometry::Sim3(Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero(), scale2) *
            geometry::Sim3(T_c2_w * T_c1_w.Inverse()))
               .Inverse();
  while (static_cast<int>(s.correspondences.size()) < n) {
    const double z = depth(rng);
    const Eigen::Vector3d X =
        T_c1_w.Inverse() * Eigen::Vector3d(u(rng) * z * 0.5, u(rng) * z * 0.4, z);
    const Eigen::Vector3d p1 = T_c1_w * X;
    Eigen::Vector3d p2 = scale2 * (T_c2_w * X);
    if (p2.z() < 0.5) continue;
    Sim3Correspondence c;
    c.pixel1 = Project(cam, p1) + pixel_noise * Eigen::Vector2d(noise(rng), noise(rng));
    c.pixel2 = Project(cam, p2) + pixel_noise * Eigen::Vector2d(noise(rng), noise(rng));
    // 3D points as a stereo/RGB-D map holds them: back-projected from the noisy keypoint with
    // a depth error of 0.5 %.
    c.p1 = Unproject(cam, c.pixel1, p1.z() * (1.0 + 0.005 * noise(rng)));
    c.p2 = Unproject(cam, c.pixel2, p2.z() * (1.0 + 0.005 * noise(rng)));
    const bool bad = unit(rng) < outliers;
    if (bad) c.p2 = scale2 * Eigen::Vector3d(u(rng) * 3.0, u(rng) * 2.0, depth(rng));
    s.correspondences.push_back(c);
    s.outlier.push_back(bad);
  }
  return s;
}

void ExpectRecovered(const Scene& s, const Sim3RansacResult& r, double tol_t, double tol_s) {
  const geometry::Sim3 E = s.S_12.Inverse() * r.S_12;
  EXPECT_LT(geometry::RotationAngle(E.rotation()), 0.01) << "rotation error (rad)";
  EXPECT_LT((r.S_12.translation() - s.S_12.translation()).norm(), tol_t);
  EXPECT_NEAR(r.S_12.scale(), s.S_12.scale(), tol_s);
  int flagged_outliers = 0, kept_inliers = 0, inliers = 0;
  for (size_t i = 0; i < s.outlier.size(); ++i) {
    if (s.outlier[i]) {
      flagged_outliers += r.inlier[i] ? 0 : 1;
    } else {
      ++inliers;
      kept_inliers += r.inlier[i] ? 1 : 0;
    }
  }
  const int outliers = static_cast<int>(s.outlier.size()) - inliers;
  // An outlier can fall within 3 pixels in both images by chance only rarely.
  EXPECT_GE(flagged_outliers, outliers - 1);
  // Pixel noise of 0.5 px in both images: the reprojection error per axis has a variance of
  // about 2 * 0.25 px^2, so e^2 exceeds 9.21 px^2 with probability exp(-9.21) ~ 1e-4 per image;
  // the 0.5 % depth noise adds parallax error, hence the 10 % margin.
  EXPECT_GE(kept_inliers, 0.9 * inliers);
}

TEST(Sim3Solver, FixedScaleWithNoiseAndOutliers) {
  const Scene s = MakeScene(150, 1.0, 0.5, 0.4, 3);
  Sim3RansacOptions options;
  options.fix_scale = true;
  const auto r = SolveSim3Ransac(Camera(), s.correspondences, options);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->S_12.scale(), 1.0);
  ExpectRecovered(s, *r, 0.05, 1e-12);
}

TEST(Sim3Solver, FreeScaleRecoversScaleDrift) {
  const Scene s = MakeScene(150, 1.7, 0.5, 0.4, 4);
  Sim3RansacOptions options;
  options.fix_scale = false;
  const auto r = SolveSim3Ransac(Camera(), s.correspondences, options);
  ASSERT_TRUE(r.has_value());
  ExpectRecovered(s, *r, 0.05, 0.02 / 1.7);
}

TEST(Sim3Solver, FixedScaleCannotExplainScaleDrift) {
  // A 1.7x scale change is not a rigid motion: with the scale fixed, far fewer points agree.
  const Scene s = MakeScene(150, 1.7, 0.5, 0.0, 5);
  Sim3RansacOptions fixed;
  fixed.fix_scale = true;
  fixed.min_inliers = 3;
  Sim3RansacOptions free = fixed;
  free.fix_scale = false;
  const auto rf = SolveSim3Ransac(Camera(), s.correspondences, fixed);
  const auto rs = SolveSim3Ransac(Camera(), s.correspondences, free);
  ASSERT_TRUE(rs.has_value());
  EXPECT_GE(rs->num_inliers, 140);
  EXPECT_LT(rf ? rf->num_inliers : 0, rs->num_inliers / 2);
}

TEST(Sim3Solver, FailsWithoutEnoughInliers) {
  const Scene s = MakeScene(60, 1.0, 1.0, 1.0, 6);  // every correspondence wrong
  Sim3RansacOptions options;
  EXPECT_FALSE(SolveSim3Ransac(Camera(), s.correspondences, options).has_value());
  const Scene few = MakeScene(10, 1.0, 0.5, 0.0, 7);
  EXPECT_FALSE(SolveSim3Ransac(Camera(), few.correspondences, options).has_value());
}

TEST(Sim3Solver, CountsInliersInBothImages) {
  Scene s = MakeScene(40, 1.0, 0.0, 0.0, 8);
  // Moving a keypoint in image 2 only must make that correspondence an outlier.
  s.correspondences[0].pixel2 += Eigen::Vector2d(10.0, 0.0);
  std::vector<bool> inlier;
  const int n = CountSim3Inliers(Camera(), s.correspondences, s.S_12, 9.21, &inlier);
  EXPECT_FALSE(inlier[0]);
  EXPECT_GE(n, 37);
}

TEST(Sim3Solver, OptionsChecked) {
  Sim3RansacOptions o;
  o.min_inliers = 2;
  EXPECT_THROW(o.Check(), InputError);
  o = {};
  o.probability = 1.0;
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace moslam::slam
