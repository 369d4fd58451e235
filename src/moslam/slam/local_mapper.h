// Local mapping (ORB-SLAM2's LocalMapping, Mur-Artal & Tardós 2017), one keyframe at a time:
// insert the keyframe (observations of the points tracking matched, covisibility update), cull
// recent map points (found/visible ratio, too few observations), triangulate new points with
// covisible keyframes (slam/new_points.h), fuse duplicates in the neighbours (slam/fuse.h), local
// bundle adjustment (optim::AdjustBundle) and redundant-keyframe culling
// (slam/keyframe_culling.h).
//
// ProcessKeyFrame is a synchronous step: System calls it in its mapping thread, or directly after
// each new keyframe in deterministic mode. It takes Map::mutex() for each step; bundle adjustment
// is copied out under the lock, solved without it and written back under it, skipping keyframes
// and points erased in between (map/map.h). Scratch state (the recent-points list) lives here.
#pragma once

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/map/map.h"
#include "moslam/optim/observation.h"
#include "moslam/slam/keyframe_database.h"

namespace moslam::slam {

struct LocalMapperOptions {
  // Metres (settings.CloseDepthMetres()): keyframe culling, and far_stereo.
  double close_depth = 0.0;
  // Local bundle adjustment after each keyframe (default on, as ORB-SLAM2); off only to measure
  // what it contributes (slam_eval --no-local-ba).
  bool local_bundle_adjustment = true;
  // Bundle adjustment's weight of the u_right row of stereo observations beyond close_depth
  // (optim::FarStereo; default kFull, as ORB-SLAM2; issue 29).
  optim::FarStereo far_stereo = optim::FarStereo::kFull;
  // The keyframes local bundle adjustment moves: the new one and at most this many of its best
  // covisible keyframes (by shared points); the other keyframes that see the local points stay
  // fixed. 0: every covisible keyframe (ORB-SLAM2), which in a room the camera keeps looking
  // around is every keyframe of the map: the "local" adjustment is then a global one, hundreds of
  // milliseconds per keyframe.
  int max_local_keyframes = 0;
  bool keyframe_culling = true;
  int num_threads = 1;  // Ceres threads in bundle adjustment
  // Monocular keyframes (ORB-SLAM2's monocular settings): 20 neighbours for triangulation and
  // fusion instead of 10, and recent points culled with 2 observations instead of 3.
  bool monocular = false;
};

// Stereo/RGB-D bundle adjustment is defined up to a rigid motion of everything (gauge freedom);
// ORB-SLAM2 anchors it with keyframe 0 and the fixed non-local keyframes. When `pose_fixed` has
// none (keyframe 0 culled or not local, every observer of the local points local), fixes the
// oldest of the first `num_local` poses (the local keyframes) so the window cannot drift freely.
void AnchorGauge(const std::vector<std::shared_ptr<map::KeyFrame>>& poses, size_t num_local,
                 std::vector<bool>* pose_fixed);

class LocalMapper {
 public:
  LocalMapper(map::Map* map, const camera::PinholeCamera& camera, double bf,
              const LocalMapperOptions& options);

  // `more_queued` (may be empty) says whether further keyframes wait; fusion and bundle
  // adjustment are then skipped to catch up, as ORB-SLAM2 does.
  void ProcessKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe,
                       const std::function<bool()>& more_queued = {});

  // With a database, each keyframe's BoW is computed (ORB-SLAM2's ComputeBoW in
  // ProcessNewKeyFrame) and the keyframe indexed once inserted. nullptr (default): neither. The
  // database must outlive the mapper; call before the first ProcessKeyFrame.
  void SetKeyFrameDatabase(KeyFrameDatabase* database) { database_ = database; }

  // ORB-SLAM2's InterruptBA: a running local bundle adjustment stops after its current iteration
  // (thread-safe; the flag is cleared when the next adjustment starts).
  void InterruptBundleAdjustment() { abort_ba_ = true; }

  // Milliseconds per processed keyframe (thread-safe copy).
  std::vector<double> StepTimes() const;
  // Local bundle adjustments run so far (keyframes mapped while others waited run none).
  int LocalBundleAdjustments() const;
  // Observations (residuals) of the last local bundle adjustment set up; 0 before the first. A
  // measure of mapping's work that does not depend on the machine (System's deterministic
  // stand-in for the mapping thread times keyframes by it).
  size_t LastAdjustmentObservations() const { return last_adjustment_observations_.load(); }

 private:
  void InsertKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe);
  void CullRecentPoints(const std::shared_ptr<map::KeyFrame>& keyframe);
  void LocalBundleAdjustment(const std::shared_ptr<map::KeyFrame>& keyframe);

  map::Map* map_;
  camera::PinholeCamera camera_;
  optim::CameraModel model_;
  LocalMapperOptions options_;
  KeyFrameDatabase* database_ = nullptr;
  std::vector<std::weak_ptr<map::MapPoint>> recent_points_;
  std::atomic<bool> abort_ba_{false};
  mutable std::mutex stats_mutex_;
  std::vector<double> step_ms_;
  int local_bundle_adjustments_ = 0;
  std::atomic<size_t> last_adjustment_observations_{0};
};

}  // namespace moslam::slam
