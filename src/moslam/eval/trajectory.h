// A camera trajectory as the evaluator sees it: timestamps (when known) and poses T_world_cam.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/geometry/sim3.h"

namespace moslam::eval {

struct Trajectory {
  // Where the trajectory came from (usually its file), used in messages.
  std::string name;
  // Seconds, non-decreasing, one per pose; empty when the file has none (KITTI poses files).
  // A repeated stamp is allowed: the TUM ground truth of fr2/desk has one (see trajectory_io.h).
  std::vector<double> timestamps;
  // Camera-to-world poses T_world_cam.
  std::vector<geometry::SE3> poses;
  // The rotation blocks exactly as read from a KITTI file, before re-orthonormalization; empty or
  // one per pose. Printed KITTI rotations are orthonormal only to ~1e-7, and evo composes the
  // matrices as read: over a 100 m RPE pair that difference moves the 6th printed digit (see
  // REFERENCE.md), so the evo convention computes relative poses from these when present.
  std::vector<Eigen::Matrix3d> raw_rotations;

  size_t size() const { return poses.size(); }
  bool empty() const { return poses.empty(); }
  bool has_timestamps() const { return !timestamps.empty(); }

  // The 4x4 pose matrix with the rotation as read when raw_rotations is set.
  Eigen::Matrix4d Matrix(size_t i) const;
  const Eigen::Vector3d& Position(size_t i) const { return poses[i].translation(); }
  // Positions as a 3xN matrix, one column per pose (the input format of geometry's alignment).
  Eigen::Matrix3Xd Positions() const;
  // Timestamp of pose i, or its index when the trajectory has no timestamps.
  double TimeOrIndex(size_t i) const;

  // The poses (and stamps, raw rotations) at `indices`, in that order; repeats allowed.
  Trajectory Subset(const std::vector<size_t>& indices) const;
  // Left-applies a similarity to every pose (positions scaled, rotated, shifted; rotations
  // rotated), as evo's PosePath3D.scale + transform do; raw rotations are rotated as well.
  void Transform(const geometry::Sim3& S_new_old);

  // Throws InputError unless timestamps (if any) and raw_rotations match the pose count.
  void CheckConsistent() const;
};

}  // namespace moslam::eval
