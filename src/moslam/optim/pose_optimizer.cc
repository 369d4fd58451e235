#include "moslam/optim/pose_optimizer.h"

#include <cmath>
#include <memory>

#include <ceres/loss_function.h>

#include "moslam/optim/cost_functions.h"
#include "moslam/optim/solver_setup.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::optim {

void PoseOptimizerOptions::Check() const {
  if (rounds < 1) ThrowInput("PoseOptimizerOptions.rounds must be >= 1 (got {})", rounds);
  if (iterations_per_round < 1) {
    ThrowInput("PoseOptimizerOptions.iterations_per_round must be >= 1 (got {})",
               iterations_per_round);
  }
  if (!(chi2_mono > 0.0)) {
    ThrowInput("PoseOptimizerOptions.chi2_mono must be > 0 (got {})", chi2_mono);
  }
  if (!(chi2_stereo > 0.0)) {
    ThrowInput("PoseOptimizerOptions.chi2_stereo must be > 0 (got {})", chi2_stereo);
  }
  if (robust_rounds < 0 || robust_rounds > rounds) {
    ThrowInput("PoseOptimizerOptions.robust_rounds must be in [0, rounds = {}] (got {})", rounds,
               robust_rounds);
  }
  if (num_threads < 1) {
    ThrowInput("PoseOptimizerOptions.num_threads must be >= 1 (got {})", num_threads);
  }
}

namespace {

std::unique_ptr<ceres::CostFunction> MakePoseOnlyCost(const CameraModel& camera,
                                                      const Observation& observation,
                                                      const Eigen::Vector3d& point_world) {
  if (observation.is_stereo()) {
    return std::make_unique<PoseOnlyReprojectionCost<3>>(camera, observation, point_world);
  }
  return std::make_unique<PoseOnlyReprojectionCost<2>>(camera, observation, point_world);
}

}  // namespace

PoseOptimizerResult OptimizePose(const CameraModel& camera, const geometry::SE3& T_cam_world_init,
                                 const std::vector<Eigen::Vector3d>& points_world,
                                 const std::vector<Observation>& observations,
                                 const PoseOptimizerOptions& options,
                                 const std::vector<bool>& initial_outlier) {
  options.Check();
  const int n = static_cast<int>(observations.size());
  MOSLAM_CHECK_EQ(points_world.size(), observations.size());
  MOSLAM_CHECK(initial_outlier.empty() || static_cast<int>(initial_outlier.size()) == n)
      << "initial_outlier has " << initial_outlier.size() << " flags for " << n << " observations";
  PoseOptimizerResult result;
  result.T_cam_world = T_cam_world_init;
  result.inlier.assign(n, false);
  if (n < 3) return result;

  std::vector<bool> outlier =
      initial_outlier.empty() ? std::vector<bool>(n, false) : initial_outlier;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs(n);
  for (int i = 0; i < n; ++i) {
    MOSLAM_CHECK(observations[i].inv_sigma2 > 0.0) << "observation " << i;
    MOSLAM_CHECK(!observations[i].is_stereo() || camera.bf > 0.0)
        << "stereo observation " << i << " with a monocular camera (bf = " << camera.bf << ")";
    costs[i] = MakePoseOnlyCost(camera, observations[i], points_world[i]);
  }

  // One problem for all rounds: a round adds the residual blocks of observations that became
  // inliers and removes those of new outliers, and the losses switch from Huber to none through
  // their wrappers (cheaper than rebuilding; see optim_benchmark.cc).
  double pose[kPoseAmbientSize];
  PoseToParameters(T_cam_world_init, pose);
  PoseManifold manifold;
  ceres::Problem problem(internal::BorrowingProblemOptions());
  problem.AddParameterBlock(pose, kPoseAmbientSize, &manifold);
  ceres::LossFunctionWrapper loss_mono(nullptr, ceres::TAKE_OWNERSHIP);
  ceres::LossFunctionWrapper loss_stereo(nullptr, ceres::TAKE_OWNERSHIP);
  std::vector<ceres::ResidualBlockId> blocks(n, nullptr);

  ceres::Solver::Options solver_options =
      internal::QuietSolverOptions(options.iterations_per_round, options.num_threads);
  // Six unknowns: the dense normal equations are the cheapest exact solver (measured against
  // DENSE_QR in optim_benchmark.cc).
  solver_options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;

  for (int round = 0; round < options.rounds; ++round) {
    const bool robust = round < options.robust_rounds;
    loss_mono.Reset(robust ? new ceres::HuberLoss(std::sqrt(options.chi2_mono)) : nullptr,
                    ceres::TAKE_OWNERSHIP);
    loss_stereo.Reset(robust ? new ceres::HuberLoss(std::sqrt(options.chi2_stereo)) : nullptr,
                      ceres::TAKE_OWNERSHIP);
    const geometry::SE3 T = PoseFromParameters(pose);
    int active = 0;
    for (int i = 0; i < n; ++i) {
      // A point behind the camera cannot be evaluated; it sits the round out as an outlier.
      const bool use = !outlier[i] && (T * points_world[i]).z() >= kMinDepth;
      if (use && blocks[i] == nullptr) {
        ceres::LossFunction* loss = observations[i].is_stereo() ? &loss_stereo : &loss_mono;
        blocks[i] = problem.AddResidualBlock(costs[i].get(), loss, pose);
      } else if (!use && blocks[i] != nullptr) {
        problem.RemoveResidualBlock(blocks[i]);
        blocks[i] = nullptr;
      }
      active += use ? 1 : 0;
    }
    // Fewer than 3 points do not constrain a pose; keep the last estimate (ORB-SLAM2 stops
    // below 10 edges).
    if (active < 3) break;
    ceres::Solver::Summary summary;
    ceres::Solve(solver_options, &problem, &summary);

    // Every observation is classified again, so an outlier whose error fell may come back.
    const geometry::SE3 T_new = PoseFromParameters(pose);
    for (int i = 0; i < n; ++i) {
      const ReprojectionCheck check =
          CheckReprojection(camera, observations[i], T_new, points_world[i]);
      const double chi2_max = observations[i].is_stereo() ? options.chi2_stereo : options.chi2_mono;
      outlier[i] = !(check.chi2 <= chi2_max) || check.depth < kMinDepth;
    }
  }

  result.T_cam_world = PoseFromParameters(pose);
  for (int i = 0; i < n; ++i) {
    result.inlier[i] = !outlier[i];
    if (outlier[i]) continue;
    ++result.num_inliers;
    result.final_cost +=
        0.5 * CheckReprojection(camera, observations[i], result.T_cam_world, points_world[i]).chi2;
  }
  return result;
}

}  // namespace moslam::optim
