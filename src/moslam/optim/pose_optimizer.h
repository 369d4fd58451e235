// Pose-only optimization (ORB-SLAM2's Optimizer::PoseOptimization, Mur-Artal & Tardós 2017):
// the camera pose is refined against fixed 3D points with a robust (Huber) loss; after each of
// several rounds every observation's chi-square error is compared to the 95 % threshold, outliers
// are excluded from the next round (and may come back if they fit again), and the last round runs
// without the robust loss. Solved with Ceres and analytic Jacobians (checked numerically in tests).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"

namespace moslam::optim {

struct PoseOptimizerOptions {
  int rounds = 4;                    // outlier-classification rounds (ORB-SLAM2: 4)
  int iterations_per_round = 10;     // Levenberg-Marquardt iterations per round (ORB-SLAM2: 10)
  double chi2_mono = kChi2Mono;      // outlier threshold on the whitened squared error, 2 DoF
  double chi2_stereo = kChi2Stereo;  // the same, 3 DoF
  // Rounds (the first ones) that use the Huber loss with delta sqrt(chi2_*). ORB-SLAM2 removes
  // the kernel while classifying after round 2 (`if(it==2) setRobustKernel(0)`), so its rounds
  // 0, 1 and 2 are robust and only the last is not: 3.
  int robust_rounds = 3;
  // Threads Ceres may use (1 for --deterministic runs).
  int num_threads = 1;
  void Check() const;  // InputError naming the field
};

struct PoseOptimizerResult {
  geometry::SE3 T_cam_world;  // refined pose
  std::vector<bool> inlier;   // per observation, after the last round
  std::vector<double> chi2;   // per observation: whitened squared error at the final pose
  int num_inliers = 0;
  double final_cost = 0.0;  // 0.5 * sum of squared whitened residuals of the inliers
};

// points_world[i] is observed as observations[i]. `initial_outlier` (empty or one flag per
// observation) marks observations to start as outliers. `weights` (empty or one per observation,
// each in (0, 1]) scale each observation's robust cost: a point believed to move (a low static
// probability, slam/static_scores.h; CFP-SLAM, Hu et al. 2022) pulls the pose less. Weights do not
// change the chi-square classification, which stays on the unweighted error. Fewer than 3
// observations: returned unchanged with every observation an outlier (an expected failure, not an
// error). Size mismatch or a weight outside (0, 1] is a broken invariant (CHECK).
PoseOptimizerResult OptimizePose(const CameraModel& camera, const geometry::SE3& T_cam_world_init,
                                 const std::vector<Eigen::Vector3d>& points_world,
                                 const std::vector<Observation>& observations,
                                 const PoseOptimizerOptions& options = {},
                                 const std::vector<bool>& initial_outlier = {},
                                 const std::vector<double>& weights = {});

}  // namespace moslam::optim
