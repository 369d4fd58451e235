// Absolute trajectory error (ATE; evo calls it APE): the error of each associated pose after the
// estimate has been aligned to the ground truth.
#pragma once

#include "moslam/eval/association.h"
#include "moslam/eval/convention.h"
#include "moslam/eval/statistics.h"
#include "moslam/eval/trajectory.h"
#include "moslam/eval/trajectory_alignment.h"

namespace moslam::eval {

struct AteOptions {
  // Association (kTum: greedy within max_dt, kEvo: nearest within max_dt) and se3 solver (Horn /
  // Umeyama). Trajectories without timestamps are matched by index in both.
  Convention convention = Convention::kTum;
  // Default se3: evaluate_ate.py always aligns rigidly; evo_ape aligns only with -a / -as.
  AlignmentMode alignment = AlignmentMode::kSe3;
  double max_dt = 0.02;  // seconds; strict (<) for tum, inclusive (<=) for evo
  double offset = 0.0;   // seconds, added to the estimate's stamps
  // Throws InputError for a max_dt that is not positive or an offset that is not finite.
  void Check() const;
  // The tool's defaults for a convention (max_dt 0.02 / 0.01 s, se3 alignment).
  static AteOptions Defaults(Convention convention);
};

struct AteResult {
  AteOptions options;
  Association association;   // indices into the input trajectories
  geometry::Sim3 alignment;  // S_gt_est that was applied to the estimate
  ComparedPoses poses;       // gt positions and aligned estimate positions, for plots
  // |p_est - p_gt| in metres (evaluate_ate.py's absolute_translational_error; evo APE trans.).
  ErrorSeries translation;
  // Angle of inv(P_est) * Q_gt in degrees (evo_ape -r angle_deg); evaluate_ate.py has no such
  // number, so both conventions compute it the evo way.
  ErrorSeries rotation;
};

// InputError when nothing associates or the alignment is undetermined (messages name the files).
AteResult ComputeAte(const Trajectory& gt, const Trajectory& est, const AteOptions& options);

}  // namespace moslam::eval
