// Aligning an estimated trajectory to its ground truth before measuring errors.
#pragma once

#include <string>

#include "moslam/eval/trajectory.h"
#include "moslam/geometry/sim3.h"

namespace moslam::eval {

enum class AlignmentMode {
  kNone,    // compare as given
  kSe3,     // best rigid transform of the positions (TUM evaluate_ate.py; evo -a)
  kSim3,    // best similarity, for monocular scale (evo -as)
  kOrigin,  // the first poses coincide (evo --align_origin)
};

// Which closed form solves the se3 alignment. Both give the same least-squares optimum; each
// convention uses its tool's method so that rounding follows the tool.
enum class AlignmentSolver {
  kHorn,     // TUM evaluate_ate.py (geometry::AlignHorn)
  kUmeyama,  // evo (geometry::AlignUmeyama); also used for kSim3 in both conventions
};

// "none", "se3", "sim3", "origin"; InputError otherwise.
AlignmentMode ParseAlignmentMode(const std::string& name);
const char* AlignmentModeName(AlignmentMode mode);

// S_gt_est for associated trajectories (pose k of `est` matches pose k of `gt`): the transform
// to left-apply to the estimate. InputError naming both trajectories when the positions do not
// determine it (fewer than 3 pairs, all on a line, an estimate without extent for sim3).
geometry::Sim3 EstimateAlignment(const Trajectory& gt, const Trajectory& est, AlignmentMode mode,
                                 AlignmentSolver solver);

}  // namespace moslam::eval
