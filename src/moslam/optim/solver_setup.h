// Solver settings shared by the optimizers (internal to optim).
#pragma once

#include <ceres/problem.h>
#include <ceres/solver.h>

namespace moslam::optim::internal {

// The problem owns nothing: cost functions, losses and the manifold live in the optimizer's
// scope, so residual blocks can be removed and added again between rounds without reallocation.
inline ceres::Problem::Options BorrowingProblemOptions() {
  ceres::Problem::Options options;
  options.cost_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  options.enable_fast_removal = true;
  return options;
}

// Levenberg-Marquardt (as g2o in ORB-SLAM2), silent.
inline ceres::Solver::Options QuietSolverOptions(int max_iterations, int num_threads) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.max_num_iterations = max_iterations;
  options.num_threads = num_threads;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

}  // namespace moslam::optim::internal
