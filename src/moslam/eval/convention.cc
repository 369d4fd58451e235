#include "moslam/eval/convention.h"

#include <algorithm>
#include <cmath>

#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::eval {

Convention ParseConvention(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "tum") return Convention::kTum;
  if (lower == "evo") return Convention::kEvo;
  ThrowInput("unknown convention '{}' (tum, evo)", name);
}

const char* ConventionName(Convention convention) {
  return convention == Convention::kTum ? "tum" : "evo";
}

double DefaultMaxDt(Convention convention) { return convention == Convention::kTum ? 0.02 : 0.01; }

void RequireComparableStamps(const Trajectory& gt, const Trajectory& est) {
  if (gt.has_timestamps() == est.has_timestamps()) return;
  const Trajectory& without = gt.has_timestamps() ? est : gt;
  ThrowInput(
      "'{}' has no timestamps but '{}' has: match both by time (give the stamps of a KITTI "
      "ground truth with --gt-times FILE) or both by index (two KITTI files)",
      without.name, gt.has_timestamps() ? gt.name : est.name);
}

Association AssociatePoses(const Trajectory& gt, const Trajectory& est, Convention convention,
                           double max_dt, double offset) {
  RequireComparableStamps(gt, est);
  if (!gt.has_timestamps()) {
    if (gt.size() != est.size()) {
      ThrowInput(
          "trajectories without timestamps are matched by index and need equal lengths, but the "
          "ground truth '{}' has {} poses and the estimate '{}' {} (give the ground truth "
          "timestamps with --gt-times to match by time)",
          gt.name, gt.size(), est.name, est.size());
    }
    return AssociateByIndex(gt.size(), est.size());
  }
  if (convention == Convention::kTum) {
    return AssociateGreedy(gt.timestamps, est.timestamps, offset, max_dt);
  }
  return AssociateNearest(gt.timestamps, est.timestamps, offset, max_dt);
}

double RotationAngleOfMatrix(const Eigen::Matrix3d& R) {
  return std::acos(std::clamp((R.trace() - 1.0) / 2.0, -1.0, 1.0));
}

Eigen::Matrix4d InverseAsEvo(const Eigen::Matrix4d& T) {
  Eigen::Matrix4d inv = Eigen::Matrix4d::Identity();
  const Eigen::Matrix3d Rt = T.topLeftCorner<3, 3>().transpose();
  inv.topLeftCorner<3, 3>() = Rt;
  inv.topRightCorner<3, 1>() = -(Rt * T.topRightCorner<3, 1>());
  return inv;
}

ComparedPoses MakeComparedPoses(const Trajectory& gt, const Trajectory& est) {
  MOSLAM_CHECK_EQ(gt.size(), est.size());
  ComparedPoses out;
  for (size_t k = 0; k < gt.size(); ++k) {
    out.times.push_back(gt.TimeOrIndex(k));
    out.gt_positions.push_back(gt.Position(k));
    out.est_positions.push_back(est.Position(k));
  }
  return out;
}

}  // namespace moslam::eval
