// Rotations: the SO(3) exponential and logarithm on unit quaternions.
//
// Frame convention for the whole project (stated here once):
//   A transform named T_a_b maps the coordinates of a point from frame b into frame a:
//   p_a = T_a_b * p_b. Composition chains matching inner frames: T_a_c = T_a_b * T_b_c, and
//   T_b_a = T_a_b.Inverse(). A camera pose in the world is T_world_cam (camera-to-world, as in
//   TUM and KITTI trajectory files); projection uses T_cam_world. The same holds for rotations
//   (R_a_b). Tangent vectors perturb on the left: T' = Exp(delta) * T.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace moslam::geometry {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Vector7d = Eigen::Matrix<double, 7, 1>;
using Matrix3x4d = Eigen::Matrix<double, 3, 4>;

// The skew-symmetric matrix with Hat(a) * b = a x b, and its inverse.
Eigen::Matrix3d Hat(const Eigen::Vector3d& v);
Eigen::Vector3d Vee(const Eigen::Matrix3d& m);

// Rotation by the angle |omega| (radians) about omega's direction.
Eigen::Quaterniond ExpSO3(const Eigen::Vector3d& omega);
// Inverse of ExpSO3, with |result| in [0, pi].
Eigen::Vector3d LogSO3(const Eigen::Quaterniond& q);
// The rotation angle of q in radians, in [0, pi]; robust near 0 and pi.
double RotationAngle(const Eigen::Quaterniond& q);

// Left Jacobian of SO(3): Exp(phi) maps a translation rho to J(phi) * rho in SE(3)'s Exp.
Eigen::Matrix3d LeftJacobianSO3(const Eigen::Vector3d& phi);
Eigen::Matrix3d LeftJacobianInverseSO3(const Eigen::Vector3d& phi);

// Nearest rotation matrix (in the Frobenius sense) to m, via SVD; fixes drift in read matrices.
Eigen::Matrix3d NearestRotation(const Eigen::Matrix3d& m);

}  // namespace moslam::geometry
