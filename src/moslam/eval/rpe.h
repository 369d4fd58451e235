// Relative pose error (RPE): the error of the motion between two poses of the estimate, compared
// with the ground-truth motion between the corresponding poses, in the two conventions of the
// field. They differ in which pairs are compared and in the error formula:
//
// kTum, TUM evaluate_rpe.py (--fixed_delta unless all_pairs):
//   - pairs (i, j) are chosen on the whole estimate (not only its associated poses): j is the
//     pose whose "index" is closest to index(i) + delta, found with the script's own binary search
//     (find_closest_index); index is the stamp (s), the frame number (f), the travelled path (m)
//     or the accumulated rotation (rad, deg). Pairs whose j is the last pose are dropped;
//   - each estimate stamp (+ offset) takes the closest gt stamp; a pair is skipped when either is
//     further than twice the median gt interval;
//   - E = ominus(ominus(P_j, P_i), ominus(Q_j, Q_i)) with ominus(a, b) = inv(a) b;
//   - without fixed delta the script compares all n*n ordered pairs, or max_pairs random ones when
//     n >= sqrt(max_pairs); with fixed delta it keeps max_pairs random pairs when it has more.
//     Python's random cannot be reproduced, so these subsamples are drawn from a seeded
//     std::mt19937_64 instead (deterministic for a seed; statistics then differ from the script's
//     in their sampling noise). max_pairs = 0 turns subsampling off.
//
// kEvo, evo_rpe (after association within max_dt and optional alignment):
//   - pairs on the associated estimate: frames f -> ids 0, d, 2d, ... (consecutive ids paired);
//     metres m -> the path travelled on the estimate accumulates pose by pose and an id is set
//     (and the sum reset) whenever it reaches delta, the first id being where it first does;
//     rad/deg -> the same with the rotation angle between consecutive poses, starting at id 0
//     (accumulated and compared in the unit of delta);
//   - all_pairs: every i with j = i + d (f); the j > i whose path from i is closest to delta,
//     within tolerance * delta (m); every j > i whose direct angle to i is within
//     tolerance * delta of delta (rad/deg);
//   - E = inv(inv(Q_i) Q_j) inv(P_i) P_j with evo's transpose-based inverse.
//
// Both compute the translation error |t(E)| (metres, scaled by a sim3 alignment) and the rotation
// error arccos((trace R(E) - 1) / 2) (reported in degrees).
#pragma once

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "moslam/eval/convention.h"
#include "moslam/eval/statistics.h"
#include "moslam/eval/trajectory.h"
#include "moslam/eval/trajectory_alignment.h"

namespace moslam::eval {

enum class DeltaUnit { kFrames, kSeconds, kMetres, kRadians, kDegrees };

// "f", "s", "m", "rad", "deg"; InputError otherwise.
DeltaUnit ParseDeltaUnit(const std::string& name);
const char* DeltaUnitName(DeltaUnit unit);

struct RpeOptions {
  Convention convention = Convention::kTum;
  // Rigid alignment leaves the RPE unchanged (up to rounding); sim3 rescales the translations.
  // Neither tool aligns by default.
  AlignmentMode alignment = AlignmentMode::kNone;
  double max_dt = 0.02;  // seconds; association for evo and for a requested alignment
  double offset = 0.0;   // seconds, added to the estimate's stamps
  double delta = 1.0;    // in delta_unit; a whole number for frames
  DeltaUnit delta_unit = DeltaUnit::kSeconds;  // kSeconds exists only in the tum convention
  bool all_pairs = false;
  size_t max_pairs = 10000;          // tum only; 0 = compare every pair
  uint64_t seed = 0;                 // tum subsampling
  double all_pairs_tolerance = 0.1;  // evo all_pairs, relative to delta (evo's rel_delta_tol)
  void Check() const;                // InputError for invalid values
  // evaluate_rpe.py with --fixed_delta --delta 1 --delta_unit s; evo_rpe's delta 1 f.
  static RpeOptions Defaults(Convention convention);
};

struct RpeResult {
  RpeOptions options;
  geometry::Sim3 alignment;  // S_gt_est applied to the estimate
  // The compared pairs (i, j) as indices into the input estimate, and the stamp (or index) of i.
  std::vector<std::pair<size_t, size_t>> pairs;
  std::vector<double> pair_times;
  ErrorSeries translation;  // metres
  ErrorSeries rotation;     // degrees
  ComparedPoses poses;      // associated positions (aligned estimate), for plots
};

// InputError when the trajectories cannot be compared (no stamps on one side, too few pairs).
RpeResult ComputeRpe(const Trajectory& gt, const Trajectory& est, const RpeOptions& options);

// TUM's find_closest_index, a binary search that returns the index of the closest value it met;
// exposed for tests. `values` must be non-empty and sorted.
size_t FindClosestIndex(const std::vector<double>& values, double target);

}  // namespace moslam::eval
