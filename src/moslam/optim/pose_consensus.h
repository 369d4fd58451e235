// Which matches agree on the camera pose, by counting (RANSAC, Fischler & Bolles 1981) rather than
// by least squares. Pose-only optimization weighs every match by its information, and a point's
// information grows with the inverse square of its depth: an object close to the camera (a cart
// pushed 1.3 m in front of it, a person walking by) outweighs the walls behind it even when it
// holds fewer matches, and once it moves the least-squares pose follows it; the static points then
// look like the outliers (docs/EVALUATION.md, "The unknown mover"). Counting decides by how many
// matches agree instead. The hypotheses are the predicted pose (the motion model's, which the
// static scene follows) and rigid poses from three matches with depth (Horn's absolute
// orientation); a sampled pose replaces the prediction only when it gathers min_gain times as
// much support, so an object that holds a slight majority of the matches for a moment cannot
// take the camera with it, while a prediction that is plainly wrong (a jerk of the camera) is.
// Each match votes with a support (1 by default): the tracker gives matches of points it has
// known for longer more (a point that has stayed put for many seconds has had more chances to
// show that it moves, and the walls have been there since the start while a cart parked in view
// two seconds ago has not), so that an object that holds even most of the matches does not
// outvote the established map.
// The optimizer then starts from the winner with the other matches flagged as outliers (which
// its rounds may take back). Deterministic: a fixed seed.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"

namespace moslam::optim {

struct PoseConsensusOptions {
  int iterations = 40;  // sampled hypotheses (>= 1)
  // A match agrees with a pose when its chi-square error is under threshold_factor x the 95 %
  // threshold. Not more: a pose that follows a close object can fit far static points within a
  // few pixels by turning a little (rotation and sideways translation look alike far away), and
  // with a looser test that pose collects them too (tested: 4x let a moved box win).
  double threshold_factor = 1.0;
  double min_gain = 1.5;  // a sample must gather this many times the prediction's inliers (>= 1)
  uint32_t seed = 1;
  void Check() const;  // InputError naming the field
};

struct PoseConsensus {
  geometry::SE3 T_cam_world;  // the winning hypothesis
  std::vector<bool> inlier;   // per observation, against it
  int num_inliers = 0;
  double support = 0.0;             // of the winner's inliers
  double prediction_support = 0.0;  // of the prediction's inliers
  int prediction_inliers = 0;
  bool replaced = false;  // a sampled pose won over the prediction
};

// points_world[i] is observed as observations[i]; points_cam[i] is the observation's own 3D
// point in the camera (from its depth), or NaN when it has none (not sampled); support[i] (empty:
// all 1) is its vote, > 0. Sizes must agree (CHECK).
PoseConsensus FindPoseConsensus(const CameraModel& camera, const geometry::SE3& T_cam_world_pred,
                                const std::vector<Eigen::Vector3d>& points_world,
                                const std::vector<Observation>& observations,
                                const std::vector<Eigen::Vector3d>& points_cam,
                                const PoseConsensusOptions& options = {},
                                const std::vector<double>& support = {});

}  // namespace moslam::optim
