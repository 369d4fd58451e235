// RANSAC estimation of the similarity between two keyframes from matched 3D points (ORB-SLAM2's
// Sim3Solver, Mur-Artal & Tardós 2017; ORB-SLAM, Mur-Artal et al. 2015, Sec. VI-B), on plain data
// so that it can be tested without a map.
//
// Each correspondence is one map point seen by keyframe 1 and one by keyframe 2, both expressed
// in their camera's frame, with the keypoint each keyframe observed it at. A hypothesis is the
// closed-form alignment of a minimal set of 3 correspondences: Horn 1987 (geometry::AlignHorn)
// with the scale fixed to 1 for stereo/RGB-D, whose maps have metric scale, and Umeyama 1991
// with a free scale for monocular maps (scale drift). A correspondence is an inlier when it
// reprojects within chi2(2 DoF, 99 %) = 9.21 * sigma^2 of its keypoint level in BOTH keyframes:
// p1 = S_12 p2 projected into camera 1 and p2 = S_12^-1 p1 into camera 2. The best hypothesis is
// refined on all its inliers (least squares in 3D, then inliers recounted).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/sim3.h"
#include "moslam/optim/observation.h"
#include "moslam/optim/sim3_optimizer.h"

namespace moslam::slam {

// p1, p2: the matched points in camera 1 and 2; pixel1, pixel2: their keypoints; sigma2_*: the
// keypoints' level variances.
using Sim3Correspondence = optim::Sim3Match;

struct Sim3RansacOptions {
  bool fix_scale = true;      // true: SE(3) (stereo/RGB-D); false: Sim(3) (monocular)
  double probability = 0.99;  // of drawing at least one all-inlier minimal set
  int min_inliers = 20;       // ORB-SLAM2's loop closing: 20
  int max_iterations = 300;   // ORB-SLAM2: 300
  double chi2 = 9.21;         // per keypoint, times its level's sigma^2 (2 DoF, 99 %)
  uint64_t seed = 1;
  void Check() const;  // InputError naming the field
};

struct Sim3RansacResult {
  geometry::Sim3 S_12;       // maps points of camera 2 into camera 1
  std::vector<bool> inlier;  // per correspondence
  int num_inliers = 0;
  int iterations = 0;
};

// Number of correspondences that reproject within the threshold in both cameras under S_12,
// flags in `inlier` (resized to correspondences.size(); may be null).
int CountSim3Inliers(const optim::CameraModel& camera,
                     const std::vector<Sim3Correspondence>& correspondences,
                     const geometry::Sim3& S_12, double chi2, std::vector<bool>* inlier);

// nullopt when there are fewer correspondences than options.min_inliers or no hypothesis gets
// that many inliers (an expected failure: the candidate is rejected).
std::optional<Sim3RansacResult> SolveSim3Ransac(
    const optim::CameraModel& camera, const std::vector<Sim3Correspondence>& correspondences,
    const Sim3RansacOptions& options);

}  // namespace moslam::slam
