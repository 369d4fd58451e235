// Levenberg-Marquardt for bundle adjustment with the points eliminated by the Schur complement
// (Triggs et al. 2000, "Bundle Adjustment - A Modern Synthesis", Sec. 6.1; the block solver of
// g2o that ORB-SLAM2's local BA runs), written for the one problem the bundle adjuster solves:
// 6-DoF poses, 3-D points and 2- or 3-row reprojection residuals.
//
// Why not Ceres here: Ceres picks a fixed-size Schur eliminator from the residual size, and a
// problem that mixes monocular (2-row) and stereo (3-row) residuals, as every RGB-D and stereo
// map does, falls back to its dynamic-size one; with the reduced camera system's sparse structure
// rebuilt on every solve, 40 % of a deterministic w_xyz run went to Ceres (perf, issue 28). Here
// the blocks are fixed-size Eigen matrices, the reduced camera system is dense (a local BA's
// keyframes see one another), and nothing is rebuilt between iterations.
//
// The iteration follows Ceres's Levenberg-Marquardt (TrustRegionMinimizer with the LM strategy)
// so that the two solvers stop at the same place: damping diag(J^T J) / radius with the diagonal
// clamped to [1e-6, 1e32], initial radius 1e4, Nielsen's radius update, steps kept when the cost
// falls by more than 1e-3 of the model's prediction, and Ceres's function (1e-6), gradient (1e-10)
// and parameter (1e-8) tolerances. A Huber loss enters as Ceres applies it when its second
// derivative is not positive: residual and Jacobian scaled by sqrt(rho'(s)).
#pragma once

#include <atomic>
#include <vector>

#include "moslam/optim/bundle_adjuster.h"

namespace moslam::optim::internal {

struct SchurLMOptions {
  int max_iterations = 10;  // steps, rejected ones included (Ceres's max_num_iterations)
  bool robust = true;       // Huber with delta sqrt(chi2_mono) / sqrt(chi2_stereo)
  double chi2_mono = kChi2Mono;
  double chi2_stereo = kChi2Stereo;
  const std::atomic<bool>* stop = nullptr;  // checked before every step; may be null
};

struct SchurLMSummary {
  // Ceres's count: the initial evaluation plus every step tried (accepted or not).
  int iterations = 0;
};

// Minimizes the active edges' cost over the poses (kPoseSize doubles each, cost_functions.h's
// layout; pose_fixed ones held) and points (3 doubles each; point_fixed ones held) in place.
// `active[e]` edges must be evaluable at the input (in front of their camera). The reduced camera
// system is dense: meant for problems of up to a few hundred free poses.
SchurLMSummary SolveSchurLM(const BundleProblem& problem, const std::vector<bool>& active,
                            const SchurLMOptions& options, double* poses, double* points);

}  // namespace moslam::optim::internal
