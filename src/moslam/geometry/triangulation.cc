#include "moslam/geometry/triangulation.h"

#include <cmath>

#include <Eigen/SVD>

namespace moslam::geometry {

std::optional<Eigen::Vector3d> TriangulateDlt(const Eigen::Vector2d& x1, const SE3& T_cam1_world,
                                              const Eigen::Vector2d& x2, const SE3& T_cam2_world) {
  const Matrix3x4d P1 = T_cam1_world.Matrix3x4();
  const Matrix3x4d P2 = T_cam2_world.Matrix3x4();
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  if (!std::isfinite(X(3)) || std::abs(X(3)) < 1e-12) return std::nullopt;
  const Eigen::Vector3d p = X.head<3>() / X(3);
  if (!p.allFinite()) return std::nullopt;
  return p;
}

}  // namespace moslam::geometry
