#include "moslam/eval/trajectory.h"

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::eval {

Eigen::Matrix4d Trajectory::Matrix(size_t i) const {
  Eigen::Matrix4d m = poses[i].Matrix();
  if (!raw_rotations.empty()) m.topLeftCorner<3, 3>() = raw_rotations[i];
  return m;
}

Eigen::Matrix3Xd Trajectory::Positions() const {
  Eigen::Matrix3Xd p(3, static_cast<Eigen::Index>(poses.size()));
  for (size_t i = 0; i < poses.size(); ++i) p.col(static_cast<Eigen::Index>(i)) = Position(i);
  return p;
}

double Trajectory::TimeOrIndex(size_t i) const {
  return has_timestamps() ? timestamps[i] : static_cast<double>(i);
}

Trajectory Trajectory::Subset(const std::vector<size_t>& indices) const {
  Trajectory out;
  out.name = name;
  out.poses.reserve(indices.size());
  for (const size_t i : indices) {
    MOSLAM_CHECK_LT(i, poses.size());
    out.poses.push_back(poses[i]);
    if (has_timestamps()) out.timestamps.push_back(timestamps[i]);
    if (!raw_rotations.empty()) out.raw_rotations.push_back(raw_rotations[i]);
  }
  return out;
}

void Trajectory::Transform(const geometry::Sim3& S_new_old) {
  const Eigen::Matrix3d R = S_new_old.rotation_matrix();
  for (geometry::SE3& pose : poses) pose = S_new_old * pose;
  for (Eigen::Matrix3d& raw : raw_rotations) raw = R * raw;
}

void Trajectory::CheckConsistent() const {
  if (has_timestamps() && timestamps.size() != poses.size()) {
    ThrowInput("{}: {} timestamps for {} poses", name, timestamps.size(), poses.size());
  }
  if (!raw_rotations.empty() && raw_rotations.size() != poses.size()) {
    ThrowInput("{}: {} raw rotations for {} poses", name, raw_rotations.size(), poses.size());
  }
}

}  // namespace moslam::eval
