// Short-loss recovery of the tracker (tracker.h, TrackerOptions::recovery_window): while the last
// tracked frame is less than the window old, the camera is assumed to have kept the velocity it
// had then. ORB-SLAM3 (Campos et al. 2021) keeps such a "recently lost" state for 5 s and
// predicts with the IMU; a visual-only system has the constant-velocity model, whose error grows
// with the time since the last frame, hence a radius that grows with the predicted travel.
#include <cmath>

#include "moslam/slam/tracker.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void TrackerOptions::Check() const {
  if (!(recovery_window >= 0.0) || !std::isfinite(recovery_window)) {
    throw InputError("TrackerOptions.recovery_window must be >= 0 seconds");
  }
  if (!(recovery_depth_fraction > 0.0) || !std::isfinite(recovery_depth_fraction)) {
    throw InputError("TrackerOptions.recovery_depth_fraction must be > 0");
  }
  if (!(recovery_speed_fraction >= 0.0) || !std::isfinite(recovery_speed_fraction)) {
    throw InputError("TrackerOptions.recovery_speed_fraction must be >= 0");
  }
  movable.Check();
  moving.Check();
  static_scores.Check();
  consensus.Check();
  young_points.Check();
}

std::optional<geometry::SE3> Tracker::RecoveryPrediction() const {
  if (options_.recovery_window <= 0.0 || !have_recovery_motion_) return std::nullopt;
  // Time going back (a replayed or restarted stream) or a long loss: nothing to predict from.
  const double dt = current_.frame.timestamp - last_.frame.timestamp;
  if (!(dt > 0.0) || dt > options_.recovery_window) return std::nullopt;
  const geometry::SE3 motion = geometry::SE3::Exp((dt / recovery_dt_) * recovery_motion_.Log());
  return motion * last_.T_cam_world;
}

std::optional<RelocalizationPrior> Tracker::RecoveryPrior() const {
  const std::optional<geometry::SE3> predicted = RecoveryPrediction();
  if (!predicted || !reference_) return std::nullopt;
  const double depth = reference_->MedianDepth();
  if (!(depth > 0.0)) return std::nullopt;  // a reference without points gives no scale
  RelocalizationPrior prior;
  prior.camera_center = predicted->Inverse().translation();
  const double travel = (prior.camera_center - last_.T_cam_world.Inverse().translation()).norm();
  prior.radius =
      options_.recovery_depth_fraction * depth + options_.recovery_speed_fraction * travel;
  return prior;
}

}  // namespace moslam::slam
