// Camera pose from 2D-3D correspondences with RANSAC, for relocalization (ORB-SLAM2's PnPsolver
// as Tracking::Relocalization uses it, Mur-Artal & Tardós 2017; EPnP: Lepetit et al. 2009).
//
// Hypotheses come from OpenCV's cv::solvePnPRansac (minimal sets solved with EPnP or AP3P) rather
// than hand-written code. OpenCV's RANSAC has one pixel threshold for every correspondence, while
// ORB-SLAM2 scales it by each keypoint's pyramid-level variance (chi2(2 DoF, 95 %) * sigma2), so
// the hypothesis is followed by ORB-SLAM2's refinement step done with per-keypoint thresholds:
// classify every correspondence, re-estimate the pose from the inliers (cv::solvePnP, iterative
// Levenberg-Marquardt from the current pose), until the inlier set no longer changes.
//
//   PnpRansacResult r = SolvePnpRansac(points_world, pixels, level_sigma2, camera);
//   if (r.success) { pose = r.T_cam_world; ... r.inlier[i] ... }
//
// A failure (too few correspondences, no hypothesis with enough inliers) is a result, not an
// exception.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"

namespace moslam::slam {

enum class PnpMinimalSolver { kEpnp, kAp3p };

struct PnpRansacOptions {
  double probability = 0.99;  // RANSAC confidence (ORB-SLAM2: 0.99)
  int min_inliers = 10;       // a pose needs at least this many inliers (ORB-SLAM2: 10)
  int max_iterations = 300;   // RANSAC iterations (ORB-SLAM2: 300)
  // Inlier test on the squared reprojection error in pixels: <= chi2 * sigma2 of the keypoint's
  // level (ORB-SLAM2: 5.991, the 2-DoF 95 % quantile).
  double chi2 = optim::kChi2Mono;
  // Refinement rounds (classify, re-estimate) after the RANSAC hypothesis.
  int refine_rounds = 5;
  // EPnP as ORB-SLAM2 (OpenCV samples 5 points for it), or AP3P (4 points: fewer iterations
  // needed at high outlier ratios). OpenCV's RANSAC seeds its sampler with a fixed state, so
  // results are repeatable run after run.
  PnpMinimalSolver solver = PnpMinimalSolver::kEpnp;
  void Check() const;  // InputError naming the field
};

struct PnpRansacResult {
  bool success = false;
  geometry::SE3 T_cam_world;
  std::vector<bool> inlier;  // per correspondence (all false when !success)
  int num_inliers = 0;
};

// points_world[i] is seen at pixels[i] (undistorted, as feature::Frame::keypoints_undistorted)
// with pixel variance level_sigma2[i] (the keypoint level's Frame::level_sigma2). Sizes must
// agree (CHECK).
PnpRansacResult SolvePnpRansac(const std::vector<Eigen::Vector3d>& points_world,
                               const std::vector<Eigen::Vector2d>& pixels,
                               const std::vector<float>& level_sigma2,
                               const optim::CameraModel& camera,
                               const PnpRansacOptions& options = {});

}  // namespace moslam::slam
