#include "moslam/eval/trajectory_alignment.h"

#include <optional>

#include "moslam/geometry/alignment.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::eval {

AlignmentMode ParseAlignmentMode(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "none") return AlignmentMode::kNone;
  if (lower == "se3") return AlignmentMode::kSe3;
  if (lower == "sim3") return AlignmentMode::kSim3;
  if (lower == "origin") return AlignmentMode::kOrigin;
  ThrowInput("unknown alignment '{}' (none, se3, sim3, origin)", name);
}

const char* AlignmentModeName(AlignmentMode mode) {
  switch (mode) {
    case AlignmentMode::kNone:
      return "none";
    case AlignmentMode::kSe3:
      return "se3";
    case AlignmentMode::kSim3:
      return "sim3";
    case AlignmentMode::kOrigin:
      return "origin";
  }
  return "?";
}

geometry::Sim3 EstimateAlignment(const Trajectory& gt, const Trajectory& est, AlignmentMode mode,
                                 AlignmentSolver solver) {
  MOSLAM_CHECK_EQ(gt.size(), est.size());
  switch (mode) {
    case AlignmentMode::kNone:
      return geometry::Sim3::Identity();
    case AlignmentMode::kOrigin:
      if (est.empty()) ThrowInput("cannot align '{}' by its origin: no poses", est.name);
      return geometry::Sim3(gt.poses.front() * est.poses.front().Inverse());
    case AlignmentMode::kSe3:
    case AlignmentMode::kSim3:
      break;
  }
  const Eigen::Matrix3Xd source = est.Positions();
  const Eigen::Matrix3Xd target = gt.Positions();
  std::optional<geometry::Sim3> S;
  if (mode == AlignmentMode::kSe3 && solver == AlignmentSolver::kHorn) {
    if (const std::optional<geometry::SE3> T = geometry::AlignHorn(source, target)) S.emplace(*T);
  } else {
    S = geometry::AlignUmeyama(source, target, mode == AlignmentMode::kSim3);
  }
  if (!S) {
    ThrowInput(
        "cannot {}-align '{}' to '{}': {} associated positions do not determine the transform "
        "(need at least 3, not all on a line)",
        AlignmentModeName(mode), est.name, gt.name, est.size());
  }
  return *S;
}

}  // namespace moslam::eval
