// Least-squares alignment of corresponding point sets: find T_target_source minimizing
// sum_i |target_i - T * source_i|^2.
//
// Too few points (< 3) or a degenerate configuration (all points on a line) is an expected
// failure: the functions return std::nullopt instead of an arbitrary rotation.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/geometry/sim3.h"

namespace moslam::geometry {

// Horn's closed form with unit quaternions (B. K. P. Horn, "Closed-form solution of absolute
// orientation using unit quaternions", JOSA A 4(4), 1987): rotation and translation only.
std::optional<SE3> AlignHorn(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target);

// Umeyama's SVD solution (S. Umeyama, "Least-squares estimation of transformation parameters
// between two point patterns", IEEE TPAMI 13(4), 1991), with an optional uniform scale. With
// with_scale == false the returned scale is exactly 1. This is what evo's -a / -as compute.
std::optional<Sim3> AlignUmeyama(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target,
                                 bool with_scale);

}  // namespace moslam::geometry
