// Two-view point triangulation by the linear (DLT) method, as ORB-SLAM2's
// LocalMapping::CreateNewMapPoints does it (Mur-Artal & Tardós 2017; Hartley & Zisserman 2003,
// section 12.2): each view contributes two rows of A X = 0 built from its 3x4 projection of
// normalized coordinates, and X is the right singular vector of the smallest singular value.
#pragma once

#include <optional>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"

namespace moslam::geometry {

// `x1`, `x2`: normalized image coordinates ((u - cx) / fx, (v - cy) / fy) of the same point in
// two cameras with poses T_cam1_world and T_cam2_world. Returns the world point, or nullopt when
// the solution is at infinity (homogeneous w ~ 0) or not finite. Depth (cheirality) is not
// checked here: callers check it together with their reprojection thresholds.
std::optional<Eigen::Vector3d> TriangulateDlt(const Eigen::Vector2d& x1, const SE3& T_cam1_world,
                                              const Eigen::Vector2d& x2, const SE3& T_cam2_world);

}  // namespace moslam::geometry
