// Refinement of the similarity between two keyframes (ORB-SLAM2's Optimizer::OptimizeSim3,
// Mur-Artal & Tardós 2017): the matched points stay fixed, S_12 minimizes the reprojection error
// of camera 2's points in image 1 and of camera 1's points in image 2, with a Huber loss; matches
// above the chi-square threshold in either image are dropped and the problem solved again. The
// residual is written as a templated functor for Ceres's automatic differentiation (exact
// derivatives; no hand-written Jacobian to check).
#pragma once

#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/sim3.h"
#include "moslam/optim/observation.h"

namespace moslam::optim {

// One matched pair of points (as slam/sim3_solver.h's Sim3Correspondence).
struct Sim3Match {
  Eigen::Vector3d p1 = Eigen::Vector3d::Zero();      // point in camera 1 (map units)
  Eigen::Vector3d p2 = Eigen::Vector3d::Zero();      // the matched point in camera 2
  Eigen::Vector2d pixel1 = Eigen::Vector2d::Zero();  // undistorted keypoint in keyframe 1
  Eigen::Vector2d pixel2 = Eigen::Vector2d::Zero();  // undistorted keypoint in keyframe 2
  double sigma2_1 = 1.0;  // pixel variance of the keypoint's pyramid level in keyframe 1
  double sigma2_2 = 1.0;  // ... in keyframe 2
};

struct Sim3OptimizerOptions {
  bool fix_scale = true;      // stereo/RGB-D: only rotation and translation change
  double chi2 = 10.0;         // per image (ORB-SLAM2: th2 = 10)
  int iterations_first = 5;   // ORB-SLAM2: 5
  int iterations_second = 5;  // after outlier removal (ORB-SLAM2: 5, or 10 with outliers)
  void Check() const;         // InputError naming the field
};

struct Sim3OptimizerResult {
  geometry::Sim3 S_12;
  std::vector<bool> inlier;  // per match, after the second round
  int num_inliers = 0;
};

// S_12_init maps camera 2 into camera 1. Camera intrinsics must be valid (CHECK).
Sim3OptimizerResult OptimizeSim3(const CameraModel& camera, const std::vector<Sim3Match>& matches,
                                 const geometry::Sim3& S_12_init,
                                 const Sim3OptimizerOptions& options = {});

}  // namespace moslam::optim
