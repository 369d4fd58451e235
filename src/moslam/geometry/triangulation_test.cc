#include "moslam/geometry/triangulation.h"

#include <gtest/gtest.h>

namespace moslam::geometry {
namespace {

Eigen::Vector2d Normalized(const SE3& T_cam_world, const Eigen::Vector3d& p_world) {
  const Eigen::Vector3d p = T_cam_world * p_world;
  return p.head<2>() / p.z();
}

TEST(TriangulateDlt, RecoversPointSeenFromTwoPoses) {
  const SE3 T1 = SE3::Identity();
  Vector6d xi;
  xi << -0.5, 0.05, 0.1, 0.02, -0.03, 0.01;
  const SE3 T2 = SE3::Exp(xi);
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(1, 2, 8), Eigen::Vector3d(-3, 0.5, 20), Eigen::Vector3d(0.1, -0.2, 2)}) {
    const auto x = TriangulateDlt(Normalized(T1, p), T1, Normalized(T2, p), T2);
    ASSERT_TRUE(x.has_value());
    EXPECT_NEAR((*x - p).norm(), 0.0, 1e-8 * p.norm());
  }
}

TEST(TriangulateDlt, NoisyObservationsStayClose) {
  const SE3 T1 = SE3::Identity();
  const SE3 T2(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-1.0, 0, 0));
  const Eigen::Vector3d p(0.5, 0.3, 10.0);
  const Eigen::Vector2d noise(1e-3, -1e-3);  // ~0.7 px at fx = 700
  const auto x = TriangulateDlt(Normalized(T1, p) + noise, T1, Normalized(T2, p), T2);
  ASSERT_TRUE(x.has_value());
  EXPECT_LT((*x - p).norm(), 0.2);  // depth error ~ z^2 / (b f) per pixel
}

TEST(TriangulateDlt, ParallelRaysGiveNoNearPoint) {
  // Pure sideways translation and identical normalized coordinates: the rays meet at infinity.
  const SE3 T1 = SE3::Identity();
  const SE3 T2(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.5, 0, 0));
  const Eigen::Vector2d x(0.1, 0.2);
  const auto p = TriangulateDlt(x, T1, x, T2);
  if (p.has_value()) {
    EXPECT_GT(p->norm(), 1e6);
  }
}

}  // namespace
}  // namespace moslam::geometry
