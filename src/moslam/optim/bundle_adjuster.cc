#include "moslam/optim/bundle_adjuster.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include <ceres/ceres.h>

#include "moslam/optim/cost_functions.h"
#include "moslam/optim/schur_lm.h"
#include "moslam/optim/solver_util.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::optim {

void BundleAdjusterOptions::Check() const {
  if (iterations_first < 0) {
    ThrowInput("BundleAdjusterOptions.iterations_first must be >= 0 (got {})", iterations_first);
  }
  if (iterations_second < 0) {
    ThrowInput("BundleAdjusterOptions.iterations_second must be >= 0 (got {})", iterations_second);
  }
  if (!(chi2_mono > 0.0)) {
    ThrowInput("BundleAdjusterOptions.chi2_mono must be > 0 (got {})", chi2_mono);
  }
  if (!(chi2_stereo > 0.0)) {
    ThrowInput("BundleAdjusterOptions.chi2_stereo must be > 0 (got {})", chi2_stereo);
  }
  if (num_threads < 1) {
    ThrowInput("BundleAdjusterOptions.num_threads must be >= 1 (got {})", num_threads);
  }
  if (schur_lm_max_poses < 0) {
    ThrowInput("BundleAdjusterOptions.schur_lm_max_poses must be >= 0 (got {})",
               schur_lm_max_poses);
  }
  if (dense_schur_max_poses < 0) {
    ThrowInput("BundleAdjusterOptions.dense_schur_max_poses must be >= 0 (got {})",
               dense_schur_max_poses);
  }
}

namespace {

void CheckProblem(const BundleProblem& problem) {
  const size_t num_poses = problem.T_cam_world.size();
  const size_t num_points = problem.points_world.size();
  MOSLAM_CHECK_EQ(problem.pose_fixed.size(), num_poses);
  MOSLAM_CHECK(problem.point_fixed.empty() || problem.point_fixed.size() == num_points)
      << "point_fixed has " << problem.point_fixed.size() << " flags for " << num_points
      << " points";
  CheckCamera(problem.camera);
  for (const BundleProblem::Edge& edge : problem.edges) {
    MOSLAM_CHECK(edge.pose >= 0 && static_cast<size_t>(edge.pose) < num_poses)
        << "edge pose index " << edge.pose << " of " << num_poses;
    MOSLAM_CHECK(edge.point >= 0 && static_cast<size_t>(edge.point) < num_points)
        << "edge point index " << edge.point << " of " << num_points;
    CheckObservation(problem.camera, edge.observation);
  }
}

// The variables of the problem in Ceres's layout: 7 doubles per pose, 3 per point.
struct State {
  std::vector<double> poses;
  std::vector<double> points;
  double* pose(int i) { return poses.data() + kPoseSize * i; }
  double* point(int i) { return points.data() + 3 * i; }
  const double* pose(int i) const { return poses.data() + kPoseSize * i; }
  const double* point(int i) const { return points.data() + 3 * i; }
};

// Whitened squared error of every edge at `state` (+infinity behind a camera).
std::vector<double> EdgeChiSquares(const BundleProblem& problem, const State& state) {
  std::vector<double> chi2(problem.edges.size());
  for (size_t e = 0; e < problem.edges.size(); ++e) {
    const BundleProblem::Edge& edge = problem.edges[e];
    const Eigen::Vector3d p_world = Eigen::Map<const Eigen::Vector3d>(state.point(edge.point));
    const Eigen::Map<const Eigen::Quaterniond> q(state.pose(edge.pose));
    const Eigen::Map<const Eigen::Vector3d> t(state.pose(edge.pose) + 4);
    chi2[e] = ChiSquare(problem.camera, edge.observation, q * p_world + t);
  }
  return chi2;
}

class Stage {
 public:
  Stage(const BundleProblem& problem, const BundleAdjusterOptions& options, State* state)
      : problem_(problem), options_(options), state_(state) {}

  // Levenberg-Marquardt over the edges with active[e]; returns the iterations run.
  int Run(const std::vector<bool>& active, bool robust, int iterations);

 private:
  int RunCeres(const std::vector<bool>& active, bool robust, int iterations,
               const std::vector<bool>& pose_used, const std::vector<bool>& point_used,
               int free_poses, int free_points);
  ceres::Solver::Options SolverOptions(int iterations, int free_poses, int free_points,
                                       const std::vector<double*>& pose_blocks,
                                       const std::vector<double*>& point_blocks) const;

  const BundleProblem& problem_;
  const BundleAdjusterOptions& options_;
  State* state_;
  std::vector<std::unique_ptr<ceres::CostFunction>> costs_;
  ceres::HuberLoss huber_mono_{std::sqrt(options_.chi2_mono)};
  ceres::HuberLoss huber_stereo_{std::sqrt(options_.chi2_stereo)};
  SE3LeftManifold manifold_;
  // Ends the solve when BundleAdjusterOptions::stop is set (Ceres runs it after every iteration).
  class StopCallback : public ceres::IterationCallback {
   public:
    explicit StopCallback(const std::atomic<bool>* stop) : stop_(stop) {}
    ceres::CallbackReturnType operator()(const ceres::IterationSummary&) override {
      return stop_ && stop_->load() ? ceres::SOLVER_TERMINATE_SUCCESSFULLY : ceres::SOLVER_CONTINUE;
    }

   private:
    const std::atomic<bool>* stop_;
  };
  mutable StopCallback stop_callback_{options_.stop};
};

int Stage::Run(const std::vector<bool>& active, bool robust, int iterations) {
  if (iterations == 0) return 0;
  const int num_poses = static_cast<int>(problem_.T_cam_world.size());
  const int num_points = static_cast<int>(problem_.points_world.size());
  std::vector<bool> pose_used(num_poses, false), point_used(num_points, false);
  for (size_t e = 0; e < problem_.edges.size(); ++e) {
    if (!active[e]) continue;
    pose_used[problem_.edges[e].pose] = true;
    point_used[problem_.edges[e].point] = true;
  }
  int free_poses = 0, free_points = 0;
  for (int i = 0; i < num_poses; ++i) free_poses += pose_used[i] && !problem_.pose_fixed[i];
  for (int j = 0; j < num_points; ++j) {
    free_points += point_used[j] && (problem_.point_fixed.empty() || !problem_.point_fixed[j]);
  }
  if (free_poses + free_points == 0) return 0;
  if (options_.solver == BundleAdjusterOptions::Solver::kSchurLM &&
      free_poses <= options_.schur_lm_max_poses) {
    internal::SchurLMOptions lm;
    lm.max_iterations = iterations;
    lm.robust = robust;
    lm.chi2_mono = options_.chi2_mono;
    lm.chi2_stereo = options_.chi2_stereo;
    lm.stop = options_.stop;
    return internal::SolveSchurLM(problem_, active, lm, state_->poses.data(), state_->points.data())
        .iterations;
  }
  return RunCeres(active, robust, iterations, pose_used, point_used, free_poses, free_points);
}

int Stage::RunCeres(const std::vector<bool>& active, bool robust, int iterations,
                    const std::vector<bool>& pose_used, const std::vector<bool>& point_used,
                    int free_poses, int free_points) {
  if (costs_.empty()) {  // built once, for both stages
    for (const BundleProblem::Edge& edge : problem_.edges) {
      if (edge.observation.is_stereo()) {
        costs_.push_back(
            std::make_unique<BundleReprojectionCost<3>>(problem_.camera, edge.observation));
      } else {
        costs_.push_back(
            std::make_unique<BundleReprojectionCost<2>>(problem_.camera, edge.observation));
      }
    }
  }
  ceres::Problem ceres_problem(BorrowingProblemOptions());
  for (size_t e = 0; e < problem_.edges.size(); ++e) {
    if (!active[e]) continue;
    const BundleProblem::Edge& edge = problem_.edges[e];
    ceres::LossFunction* loss = nullptr;
    if (robust) loss = edge.observation.is_stereo() ? &huber_stereo_ : &huber_mono_;
    ceres_problem.AddResidualBlock(costs_[e].get(), loss, state_->pose(edge.pose),
                                   state_->point(edge.point));
  }
  std::vector<double*> pose_blocks, point_blocks;
  for (size_t i = 0; i < pose_used.size(); ++i) {
    if (!pose_used[i]) continue;
    double* block = state_->pose(static_cast<int>(i));
    pose_blocks.push_back(block);
    ceres_problem.SetManifold(block, &manifold_);
    if (problem_.pose_fixed[i]) ceres_problem.SetParameterBlockConstant(block);
  }
  for (size_t j = 0; j < point_used.size(); ++j) {
    if (!point_used[j]) continue;
    double* block = state_->point(static_cast<int>(j));
    point_blocks.push_back(block);
    if (!problem_.point_fixed.empty() && problem_.point_fixed[j]) {
      ceres_problem.SetParameterBlockConstant(block);
    }
  }
  const State before = *state_;
  ceres::Solver::Summary summary;
  ceres::Solve(SolverOptions(iterations, free_poses, free_points, pose_blocks, point_blocks),
               &ceres_problem, &summary);
  if (!summary.IsSolutionUsable()) {
    *state_ = before;
    return 0;
  }
  return summary.num_successful_steps + summary.num_unsuccessful_steps;
}

ceres::Solver::Options Stage::SolverOptions(int iterations, int free_poses, int free_points,
                                            const std::vector<double*>& pose_blocks,
                                            const std::vector<double*>& point_blocks) const {
  ceres::Solver::Options options = QuietSolverOptions(iterations, options_.num_threads);
  if (options_.stop) options.callbacks.push_back(&stop_callback_);
  if (free_poses == 0 || free_points == 0) {
    // Nothing to eliminate (or nothing left after elimination): the normal equations are block
    // diagonal or small.
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    return options;
  }
  // Schur complement on the points (Triggs et al. 2000): eliminate the points first, solve the
  // reduced camera system; dense when it is small (a local BA's dozen keyframes), sparse beyond.
  options.linear_solver_type =
      free_poses <= options_.dense_schur_max_poses ? ceres::DENSE_SCHUR : ceres::SPARSE_SCHUR;
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  for (double* block : point_blocks) ordering->AddElementToGroup(block, 0);
  for (double* block : pose_blocks) ordering->AddElementToGroup(block, 1);
  options.linear_solver_ordering = ordering;
  return options;
}

double InlierCost(const std::vector<double>& chi2, const std::vector<bool>& inlier) {
  double cost = 0.0;
  for (size_t e = 0; e < chi2.size(); ++e) {
    if (inlier[e]) cost += 0.5 * chi2[e];
  }
  return cost;
}

}  // namespace

BundleResult AdjustBundle(const BundleProblem& problem, const BundleAdjusterOptions& options) {
  options.Check();
  CheckProblem(problem);
  BundleResult result;
  result.T_cam_world = problem.T_cam_world;
  result.points_world = problem.points_world;
  const size_t num_edges = problem.edges.size();
  result.edge_inlier.assign(num_edges, false);
  if (num_edges == 0) return result;

  State state;
  state.poses.resize(kPoseSize * problem.T_cam_world.size());
  state.points.resize(3 * problem.points_world.size());
  for (size_t i = 0; i < problem.T_cam_world.size(); ++i) {
    PackPose(problem.T_cam_world[i], state.pose(static_cast<int>(i)));
  }
  for (size_t j = 0; j < problem.points_world.size(); ++j) {
    Eigen::Map<Eigen::Vector3d> point(state.point(static_cast<int>(j)));
    point = problem.points_world[j];
  }
  const State initial = state;
  const std::vector<double> initial_chi2 = EdgeChiSquares(problem, state);

  // ORB-SLAM2's schedule (LocalBundleAdjustment): a robust stage over every edge that can be
  // evaluated, then the edges above the chi-square threshold or behind a camera are dropped and
  // a second stage runs without the robust loss.
  auto threshold = [&](size_t e) {
    return Chi2Threshold(problem.edges[e].observation, options.chi2_mono, options.chi2_stereo);
  };
  std::vector<bool> active(num_edges);
  for (size_t e = 0; e < num_edges; ++e) active[e] = std::isfinite(initial_chi2[e]);
  Stage stage(problem, options, &state);
  result.iterations = stage.Run(active, options.robust, options.iterations_first);
  std::vector<double> chi2 = EdgeChiSquares(problem, state);
  for (size_t e = 0; e < num_edges; ++e) active[e] = chi2[e] <= threshold(e);
  if (!(options.stop && options.stop->load())) {
    result.iterations += stage.Run(active, false, options.iterations_second);
  }
  chi2 = EdgeChiSquares(problem, state);
  for (size_t e = 0; e < num_edges; ++e) result.edge_inlier[e] = chi2[e] <= threshold(e);

  result.initial_cost = InlierCost(initial_chi2, result.edge_inlier);
  result.final_cost = InlierCost(chi2, result.edge_inlier);
  // Poses the solver did not move keep their input value bitwise (unpacking renormalizes).
  for (size_t i = 0; i < problem.T_cam_world.size(); ++i) {
    const int k = static_cast<int>(i);
    if (!std::equal(state.pose(k), state.pose(k) + kPoseSize, initial.pose(k))) {
      result.T_cam_world[i] = UnpackPose(state.pose(k));
    }
  }
  for (size_t j = 0; j < problem.points_world.size(); ++j) {
    result.points_world[j] = Eigen::Map<const Eigen::Vector3d>(state.point(static_cast<int>(j)));
  }
  return result;
}

void WeighFarStereo(const FarStereoWeighting& far, BundleProblem* problem) {
  far.ApplyToAll(problem->camera.bf, problem->T_cam_world.size(), problem->edges,
                 [](BundleProblem::Edge& e) -> Observation& { return e.observation; });
}

}  // namespace moslam::optim
