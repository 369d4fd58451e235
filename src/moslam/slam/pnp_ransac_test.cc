// PnP RANSAC on synthetic correspondences: exact 3D points seen by a known camera with pixel noise
// scaled by a random pyramid level, mixed with uniformly random outliers.
#include "moslam/slam/pnp_ransac.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "moslam/testing/error_of.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

optim::CameraModel Camera() {
  optim::CameraModel c;
  c.fx = c.fy = 520.0;
  c.cx = 320.0;
  c.cy = 240.0;
  return c;
}

struct Problem {
  geometry::SE3 T_cam_world;
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<float> sigma2;
  std::vector<bool> is_outlier;
};

// `n` correspondences, a fraction `outliers` of them with a random pixel; inliers carry Gaussian
// noise of 1 pixel times the level's scale (ORB-SLAM2's level sigma, scale factor 1.2).
Problem MakeProblem(int n, double outliers, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::normal_distribution<double> noise(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, 7);
  Problem p;
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -1.0, 0.2).normalized();
  p.T_cam_world =
      geometry::SE3(Eigen::Matrix3d(Eigen::AngleAxisd(0.4, axis)), Eigen::Vector3d(0.5, -0.2, 1.0));
  const geometry::SE3 T_world_cam = p.T_cam_world.Inverse();
  const optim::CameraModel cam = Camera();
  for (int i = 0; i < n; ++i) {
    // A point in the camera's view, 2-12 m away.
    const double z = 2.0 + 10.0 * u01(rng);
    const double x = (640.0 * u01(rng) - cam.cx) * z / cam.fx;
    const double y = (480.0 * u01(rng) - cam.cy) * z / cam.fy;
    p.points.push_back(T_world_cam * Eigen::Vector3d(x, y, z));
    const int l = level(rng);
    const double scale = std::pow(1.2, l);
    p.sigma2.push_back(static_cast<float>(scale * scale));
    const bool outlier = u01(rng) < outliers;
    p.is_outlier.push_back(outlier);
    if (outlier) {
      p.pixels.emplace_back(640.0 * u01(rng), 480.0 * u01(rng));
    } else {
      p.pixels.emplace_back(cam.fx * x / z + cam.cx + scale * noise(rng),
                            cam.fy * y / z + cam.cy + scale * noise(rng));
    }
  }
  return p;
}

double RotationErrorDeg(const geometry::SE3& a, const geometry::SE3& b) {
  return Eigen::AngleAxisd(a.rotation_matrix().transpose() * b.rotation_matrix()).angle() * 180.0 /
         M_PI;
}

void ExpectRecovers(const Problem& p, const PnpRansacOptions& options) {
  const PnpRansacResult r = SolvePnpRansac(p.points, p.pixels, p.sigma2, Camera(), options);
  ASSERT_TRUE(r.success);
  ASSERT_EQ(r.inlier.size(), p.points.size());
  // 1 px noise at 2-12 m over ~100 inliers: the pose is good to a few centimetres / tenths of a
  // degree; a wrong hypothesis is off by metres.
  EXPECT_LT(RotationErrorDeg(r.T_cam_world, p.T_cam_world), 0.3);
  EXPECT_LT((r.T_cam_world.translation() - p.T_cam_world.translation()).norm(), 0.05);
  int kept = 0, inliers = 0, outliers_accepted = 0, outliers = 0;
  for (size_t i = 0; i < p.points.size(); ++i) {
    if (p.is_outlier[i]) {
      ++outliers;
      outliers_accepted += r.inlier[i] ? 1 : 0;
    } else {
      ++inliers;
      kept += r.inlier[i] ? 1 : 0;
    }
  }
  EXPECT_GT(outliers, 0);
  // A random pixel falls within ~2.4 sigma of the true one by chance with probability ~1e-3.
  EXPECT_LE(outliers_accepted, 2);
  // The 95 % chi-square gate keeps ~95 % of the inliers.
  EXPECT_GE(kept, 0.88 * inliers);
  EXPECT_EQ(r.num_inliers, kept + outliers_accepted);
}

TEST(PnpRansac, RecoversPoseWith30PercentOutliers) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    ExpectRecovers(MakeProblem(150, 0.3, seed), {});
  }
}

TEST(PnpRansac, RecoversPoseWith50PercentOutliersEpnpAndAp3p) {
  PnpRansacOptions ap3p;
  ap3p.solver = PnpMinimalSolver::kAp3p;
  for (unsigned seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE(seed);
    const Problem p = MakeProblem(150, 0.5, 100 + seed);
    ExpectRecovers(p, {});
    ExpectRecovers(p, ap3p);
  }
}

TEST(PnpRansac, PureOutliersGiveNoPose) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const Problem p = MakeProblem(100, 1.0, 200 + seed);
    const PnpRansacResult r = SolvePnpRansac(p.points, p.pixels, p.sigma2, Camera());
    EXPECT_FALSE(r.success) << seed;
    EXPECT_EQ(r.num_inliers, 0);
    EXPECT_EQ(r.inlier, std::vector<bool>(100, false));
  }
}

TEST(PnpRansac, TooFewCorrespondencesGiveNoPose) {
  const Problem p = MakeProblem(8, 0.0, 7);
  EXPECT_FALSE(SolvePnpRansac(p.points, p.pixels, p.sigma2, Camera()).success);
  const PnpRansacResult empty = SolvePnpRansac({}, {}, {}, Camera());
  EXPECT_FALSE(empty.success);
  EXPECT_TRUE(empty.inlier.empty());
}

TEST(PnpRansac, OptionsCheckNamesField) {
  PnpRansacOptions o;
  o.probability = 1.5;
  EXPECT_NE(moslam::testing::ErrorOf([&] { o.Check(); }).find("probability"), std::string::npos);
  o = {};
  o.min_inliers = 2;
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace moslam::slam
