// Pose-only optimization of a frame against matched map points (ORB-SLAM2's
// Optimizer::PoseOptimization as tracking uses it, Mur-Artal & Tardós 2017): each matched
// keypoint becomes a monocular or stereo observation (RGB-D/stereo keypoints with a right
// coordinate give the 3-DoF residual), whitened by its pyramid level's variance, and
// optim::OptimizePose refines the pose with Huber loss and chi-square outlier rounds.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "moslam/feature/frame.h"
#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"
#include "moslam/optim/pose_optimizer.h"

namespace moslam::slam {

// The observations of keypoints `indices` of `frame`, far stereo rows weighed by `far`.
std::vector<optim::Observation> FrameObservations(const feature::Frame& frame,
                                                  const std::vector<size_t>& indices,
                                                  const optim::FarStereoWeighting& far = {});

// points_world[k] is matched to keypoint indices[k] of `frame` (same size: CHECK). `weights`:
// empty, or one per match in (0, 1]; `initial_outlier`: empty, or one flag per match
// (optim::OptimizePose). Far stereo rows at full weight (optim::FarStereo::kFull).
optim::PoseOptimizerResult OptimizeFramePose(
    const optim::CameraModel& camera, const feature::Frame& frame,
    const std::vector<size_t>& indices, const std::vector<Eigen::Vector3d>& points_world,
    const geometry::SE3& T_cam_world_init, int num_threads = 1,
    const std::vector<double>& weights = {}, const std::vector<bool>& initial_outlier = {});

}  // namespace moslam::slam
