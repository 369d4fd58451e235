#include "moslam/eval/ate.h"

#include <cmath>

#include "moslam/util/error.h"

namespace moslam::eval {

void AteOptions::Check() const {
  if (!(max_dt > 0) || !std::isfinite(max_dt)) {
    ThrowInput("max_dt must be a positive number of seconds, got {}", max_dt);
  }
  if (!std::isfinite(offset)) ThrowInput("offset must be finite, got {}", offset);
}

AteOptions AteOptions::Defaults(Convention convention) {
  AteOptions options;
  options.convention = convention;
  options.max_dt = DefaultMaxDt(convention);
  return options;
}

AteResult ComputeAte(const Trajectory& gt, const Trajectory& est, const AteOptions& options) {
  options.Check();
  AteResult result;
  result.options = options;
  result.association = AssociatePoses(gt, est, options.convention, options.max_dt, options.offset);
  if (result.association.size() == 0) {
    ThrowInput("no pose of '{}' matches one of '{}' within {} s (offset {} s)", est.name, gt.name,
               options.max_dt, options.offset);
  }
  const Trajectory matched_gt = gt.Subset(result.association.gt);
  Trajectory matched_est = est.Subset(result.association.est);
  const AlignmentSolver solver =
      options.convention == Convention::kTum ? AlignmentSolver::kHorn : AlignmentSolver::kUmeyama;
  result.alignment = EstimateAlignment(matched_gt, matched_est, options.alignment, solver);
  matched_est.Transform(result.alignment);

  std::vector<double> translation;
  std::vector<double> rotation;
  translation.reserve(matched_gt.size());
  rotation.reserve(matched_gt.size());
  for (size_t k = 0; k < matched_gt.size(); ++k) {
    translation.push_back((matched_est.Position(k) - matched_gt.Position(k)).norm());
    const Eigen::Matrix4d E = InverseAsEvo(matched_est.Matrix(k)) * matched_gt.Matrix(k);
    rotation.push_back(RotationAngleOfMatrix(E.topLeftCorner<3, 3>()) * 180.0 / M_PI);
  }
  result.translation = MakeSeries(std::move(translation));
  result.rotation = MakeSeries(std::move(rotation));
  result.poses = MakeComparedPoses(matched_gt, matched_est);
  return result;
}

}  // namespace moslam::eval
