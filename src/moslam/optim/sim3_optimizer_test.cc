#include "moslam/optim/sim3_optimizer.h"

#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/so3.h"

namespace moslam::optim {
namespace {

CameraModel Camera() {
  CameraModel c;
  c.fx = c.fy = 500.0;
  c.cx = 320.0;
  c.cy = 240.0;
  return c;
}

Eigen::Vector2d Project(const CameraModel& c, const Eigen::Vector3d& p) {
  return {c.fx * p.x() / p.z() + c.cx, c.fy * p.y() / p.z() + c.cy};
}

// Exact matches under S_12 (scale `scale`), with `num_outliers` pixels in image 1 moved by 30 px.
std::vector<Sim3Match> Matches(const geometry::Sim3& S_12, int n, int num_outliers) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), depth(2.0, 6.0);
  std::vector<Sim3Match> out;
  while (static_cast<int>(out.size()) < n) {
    const double z = depth(rng);
    Sim3Match m;
    m.p2 = Eigen::Vector3d(u(rng) * z * 0.4, u(rng) * z * 0.3, z);
    m.p1 = S_12 * m.p2;
    if (m.p1.z() < 0.5) continue;
    m.pixel1 = Project(Camera(), m.p1);
    m.pixel2 = Project(Camera(), m.p2);
    if (static_cast<int>(out.size()) < num_outliers) m.pixel1 += Eigen::Vector2d(30.0, -20.0);
    out.push_back(m);
  }
  return out;
}

TEST(Sim3Optimizer, RecoversFromPerturbedStartAndFlagsOutliers) {
  for (const bool fix_scale : {true, false}) {
    const geometry::Sim3 truth(geometry::ExpSO3(Eigen::Vector3d(0.1, -0.2, 0.05)),
                               Eigen::Vector3d(0.3, -0.1, 0.2), fix_scale ? 1.0 : 0.7);
    const auto matches = Matches(truth, 80, 8);
    const geometry::Sim3 init =
        geometry::Sim3(geometry::ExpSO3(Eigen::Vector3d(0.01, 0.01, -0.01)),
                       Eigen::Vector3d(0.02, 0.02, 0.0), fix_scale ? 1.0 : 1.05) *
        truth;
    Sim3OptimizerOptions options;
    options.fix_scale = fix_scale;
    options.iterations_first = 10;
    options.iterations_second = 10;
    const Sim3OptimizerResult r = OptimizeSim3(Camera(), matches, init, options);
    EXPECT_EQ(r.num_inliers, 72) << "fix_scale " << fix_scale;
    for (int k = 0; k < 8; ++k) EXPECT_FALSE(r.inlier[k]);
    EXPECT_LT(geometry::RotationAngle(r.S_12.rotation() * truth.rotation().conjugate()), 1e-6);
    EXPECT_LT((r.S_12.translation() - truth.translation()).norm(), 1e-5);
    EXPECT_NEAR(r.S_12.scale(), truth.scale(), 1e-6);
  }
}

}  // namespace
}  // namespace moslam::optim
