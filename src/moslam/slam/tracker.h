// Tracking (ORB-SLAM2's Tracking, Mur-Artal & Tardós 2017) for stereo, RGB-D and monocular
// frames: map initialization from the first frame with enough depth points, or, monocular, from
// two views (slam/mono_initializer.h; tracker_mono.cc); per frame a constant-velocity
// motion model (projection search of the last frame's points), falling back to descriptor
// matching against the reference keyframe; then the local map (covisible keyframes and their
// points, projection search); pose-only optimization with Huber loss and chi-square rejection
// (optim::OptimizePose); the keyframe decision; and keyframe creation with new close points.
//
// Threads: Track() runs in the caller's thread. It holds Map::mutex() for each map-reading step
// and for keyframe creation (map/map.h states the locking design); the new keyframe is handed to
// the KeyFrameSink after the lock is released (the sink may block on a full queue).
// Scratch state (which local points were already matched this frame, ORB-SLAM2's
// mnTrackReferenceForFrame / mnLastFrameSeen) lives in sets inside this class, not on the map.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/feature/frame.h"
#include "moslam/geometry/se3.h"
#include "moslam/map/map.h"
#include "moslam/optim/observation.h"
#include "moslam/optim/pose_consensus.h"
#include "moslam/slam/keyframe_database.h"
#include "moslam/slam/mono_initializer.h"
#include "moslam/slam/movable_points.h"
#include "moslam/slam/moving_keypoints.h"
#include "moslam/slam/moving_regions.h"
#include "moslam/slam/relocalizer.h"
#include "moslam/slam/static_scores.h"
#include "moslam/slam/young_points.h"

namespace moslam::slam {

// Where new keyframes go (local mapping), and what tracking may ask of it.
class KeyFrameSink {
 public:
  virtual ~KeyFrameSink() = default;
  // True when local mapping is idle (ORB-SLAM2's AcceptKeyFrames).
  virtual bool MappingIdle() const = 0;
  // Keyframes waiting in the queue.
  virtual size_t QueuedKeyFrames() const = 0;
  // Called without the map lock held.
  virtual void InsertKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe) = 0;
  // Tracking wants a keyframe in while mapping is busy: stop the running local bundle adjustment
  // (ORB-SLAM2's InterruptBA). Default: nothing.
  virtual void InterruptMapping() {}
};

struct TrackerOptions {
  double close_depth = 0.0;  // metres (settings.CloseDepthMetres()): close/far threshold
  // Pose optimization's weight of far stereo rows (optim::FarStereo, beyond close_depth).
  optim::FarStereo far_stereo = optim::FarStereo::kFull;
  int min_init_points = 500;              // depth points needed to initialize (ORB-SLAM2: 500)
  int max_frames_between_keyframes = 10;  // ORB-SLAM2: fps
  int min_inliers = 30;                   // local-map inliers for "ok" (ORB-SLAM2: 30)
  int num_threads = 1;                    // for the pose optimizer
  // Monocular: two-view initialization, no depth, ORB-SLAM2's monocular thresholds.
  bool monocular = false;
  MonoInitializerOptions initializer;  // monocular only
  int min_init_features = 100;  // monocular: keypoints of an initialization frame (ORB-SLAM2)
  int min_init_matches = 100;   // monocular: matches with the reference (ORB-SLAM2: 100)
  // A short loss (ORB-SLAM3's "recently lost" state, Campos et al. 2021, which predicts with the
  // IMU; here the constant-velocity model): for recovery_window seconds after the last tracked
  // frame, a lost frame first searches that frame's points again at the pose the last velocity
  // predicts (twice the motion model's radius), and a relocalization must put the camera within
  // recovery_depth_fraction x the reference keyframe's median depth + recovery_speed_fraction x
  // the distance that velocity covers, of the predicted centre (slam/tracker_recovery.cc). After
  // the window any relocalization is taken (a kidnapped camera). recovery_window 0: ORB-SLAM2.
  double recovery_window = 2.0;           // seconds
  double recovery_depth_fraction = 0.25;  // of the median scene depth (scale-free, monocular too)
  double recovery_speed_fraction = 0.5;   // of the distance predicted since the last frame
  // Map points on movable objects, judged by each tracked frame's mask and depth
  // (slam/movable_points.h); mask evidence on, free space off by default.
  MovablePointsOptions movable;
  // Keyframe keypoints seen moving since a few frames back seed no map point
  // (slam/moving_keypoints.h).
  MovingKeypointsOptions moving;
  // Static probabilities of map points from their residuals (slam/static_scores.h): weights in
  // pose optimization, and points judged moving often enough are erased.
  StaticScoreOptions static_scores;
  // Stereo / RGB-D: before each pose optimization the matches that agree on the pose are found by
  // counting (optim/pose_consensus.h), so that a close object with fewer matches but more
  // information cannot take the camera along when it moves; the optimizer starts from them.
  bool pose_consensus = true;
  optim::PoseConsensusOptions consensus;
  // Stereo / RGB-D: recently made points that fit a pose of their own much better than the one
  // the long-known points give are left out of the frame's pose (slam/young_points.h).
  YoungPointOptions young_points;
  // A motion model that keeps under a quarter of the last frame's inliers is cross-checked with
  // the reference keyframe's descriptor matches, the better pose kept (a prediction far off
  // among repeated structure; Tracker::CrossCheckWithReference).
  bool motion_cross_check = true;
  // ORB-SLAM2's localization mode (mbOnlyTracking): frames are tracked against the map and
  // relocalized when lost, but no keyframe is made and no map point erased (neither by masks nor
  // by residuals), so the map stays as it was loaded (slam/system.h, SystemOptions::localization).
  bool localization = false;
  void Check() const;  // InputError naming the field
};

// What tracking reads of a frame beyond its keypoints: the movable-object mask the extractor
// used and, RGB-D, the depth image (slam/movable_points.h). Either may be empty.
struct FrameImages {
  cv::Mat mask;   // CV_8UC1, non-zero = movable
  cv::Mat depth;  // CV_32FC1 metres
};

enum class TrackStatus { kNotInitialized, kInitialized, kOk, kLost };

struct TrackOutcome {
  TrackStatus status = TrackStatus::kNotInitialized;
  std::string reason;
  int num_matches = 0;
  int num_inliers = 0;
  bool new_keyframe = false;
  bool relocalized = false;    // the pose came from relocalization (slam/relocalizer.h)
  bool recovered = false;      // lost before, tracked again from the predicted pose
  MovablePointsStats movable;  // map points judged (and erased) by this frame's mask and depth
  int residual_erased = 0;     // map points erased as moving by their residuals (static_scores.h)
  // Keypoints this frame found inconsistent with the camera's motion: matched points that
  // static_scores.h judges moving and are outliers now, and, on a keyframe, keypoints seen
  // moving (moving_keypoints.h). What slam/moving_regions.h grows mask regions from.
  std::vector<InconsistentKeypoint> inconsistent;
  geometry::SE3 T_cam_world;
  double track_ms = 0.0, local_map_ms = 0.0, keyframe_ms = 0.0;
};

class Tracker {
 public:
  Tracker(map::Map* map, const camera::PinholeCamera& camera, double bf,
          const TrackerOptions& options, KeyFrameSink* sink);

  TrackOutcome Track(feature::Frame frame, const FrameImages& images = {});

  // Enables relocalization (ORB-SLAM2's Tracking::Relocalization, slam/relocalizer.h): when the
  // motion model and the reference keyframe both fail, and on every frame while lost, the frame
  // is relocalized against the database's candidates. nullptr (the default): no relocalization;
  // a lost tracker keeps trying the reference keyframe. The database must outlive the tracker
  // and is read under Map::mutex().
  void SetKeyFrameDatabase(const KeyFrameDatabase* database) { database_ = database; }

  // Per processed frame: its reference keyframe and the pose relative to it (ORB-SLAM2's
  // mlRelativeFramePoses), or no keyframe when the frame was lost / before initialization.
  struct FramePose {
    double timestamp = 0.0;
    std::shared_ptr<map::KeyFrame> reference;
    geometry::SE3 T_cam_ref;
  };
  const std::vector<FramePose>& frame_poses() const { return frame_poses_; }
  bool initialized() const { return initialized_; }
  // Starts on a map loaded from a file (mapio/map_file.h): initialized but lost, so the first
  // frame is relocalized in the map (needs the keyframe database) instead of starting a new one.
  void StartFromLoadedMap();
  // Monocular: initial maps rejected after bundle adjustment (ORB-SLAM2 resets then).
  int rejected_initializations() const { return rejected_initializations_; }

  struct CurrentFrame {
    feature::Frame frame;
    geometry::SE3 T_cam_world;
    std::vector<std::shared_ptr<map::MapPoint>> points;  // per keypoint
    std::vector<bool> outlier;                           // per keypoint
  };
  // What a viewer draws of the last Track() (System::View): its frame with the map point each
  // keypoint matched (a tracked frame becomes the last frame, its outliers dropped; a lost one
  // stays current), and the local map it was tracked against. Read in the tracking thread; the
  // points' fields under Map::mutex().
  const CurrentFrame& viewed_frame() const {
    return current_.frame.keypoints.empty() ? last_ : current_;
  }
  const std::vector<std::shared_ptr<map::MapPoint>>& local_points() const { return local_points_; }

 private:
  bool Initialize();
  // Monocular initialization (tracker_mono.cc).
  TrackOutcome InitializeMonocular();
  bool CreateInitialMonocularMap(const std::vector<std::pair<size_t, size_t>>& pairs,
                                 const MonoInitialization& init, std::string* reason);
  void RefreshLastFrame();
  int TrackWithMotionModel();
  int TrackReferenceKeyFrame();
  // After a motion model that kept few inliers: the reference keyframe tried too, the better
  // of the two kept; returns its inliers.
  int CrossCheckWithReference(int motion_inliers);
  bool Relocalize(TrackOutcome* out);
  // Short-loss recovery (tracker_recovery.cc): the predicted pose while recently lost, the
  // prior it gives relocalization.
  std::optional<geometry::SE3> RecoveryPrediction() const;
  std::optional<RelocalizationPrior> RecoveryPrior() const;
  // The last frame's points searched around `predicted` (radius_scale x the motion model's
  // radius, then twice that), and the pose optimized; returns the inliers. The motion model is
  // this with the constant-velocity prediction.
  int TrackFromPrediction(const geometry::SE3& predicted, float radius_scale = 1.0f);
  int OptimizeCurrentPose();
  optim::FarStereoWeighting FarWeighting() const {
    return {options_.far_stereo, options_.close_depth};
  }
  int DiscardOutliers();
  int TrackLocalMap(TrackOutcome* out);
  // Movable objects (tracker_movable.cc): the local points this frame did not match, judged by
  // its mask and depth (movable_points.h); the keyframe-to-be's keypoints that moved against
  // the frame frame_gap back (moving_keypoints.h); the tracked frame kept for that check.
  MovablePointsStats JudgeLocalPoints(const FrameImages& images);
  // The matched points' residuals after the local-map optimization update their static
  // probabilities (static_scores.h); points judged moving are erased (returns how many) and the
  // inconsistent keypoints collected.
  int JudgeResiduals(std::vector<InconsistentKeypoint>* inconsistent);
  // The established-points check of the pose just optimized from matches `index` (keypoints of
  // the current frame, their map points at `points`, optimized from `start`): replaces *result
  // when the young points move (young_points.h). Stereo / RGB-D.
  void CheckYoungPoints(const std::vector<size_t>& index,
                        const std::vector<Eigen::Vector3d>& points, const geometry::SE3& start,
                        optim::PoseOptimizerResult* result);
  // The keyframe-to-be's keypoints flagged moving, as inconsistent keypoints.
  void AppendMovingKeypoints(std::vector<InconsistentKeypoint>* inconsistent) const;
  void FlagMovingKeypoints();
  void RememberFrame();
  void UpdateLocalKeyFrames();
  void UpdateLocalPoints();
  void SearchLocalPoints();
  bool NeedNewKeyFrame() const;
  std::shared_ptr<map::KeyFrame> CreateKeyFrame();
  int SearchByProjection(const std::vector<std::shared_ptr<map::MapPoint>>& candidates,
                         float radius, bool check_right);
  void RecordPose(bool ok);

  map::Map* map_;
  camera::PinholeCamera camera_;
  optim::CameraModel model_;
  TrackerOptions options_;
  KeyFrameSink* sink_;

  bool initialized_ = false;
  CurrentFrame current_;
  CurrentFrame last_;
  bool last_ok_ = false;
  bool have_velocity_ = false;
  geometry::SE3 velocity_;  // T_cam_world(k) * T_world_cam(k-1)
  // The pose the motion model (or a short-loss recovery) predicted for the current frame, before
  // any optimization: where the established-points check starts (young_points.h). Reset each frame.
  std::optional<geometry::SE3> prediction_;
  bool young_points_moved_ = false;  // the check replaced a pose of the current frame
  // The last frame-to-frame velocity (not one spanning a loss) and its interval in seconds,
  // for the short-loss prediction (tracker_recovery.cc); kept through relocalized frames.
  geometry::SE3 recovery_motion_;
  double recovery_dt_ = 0.0;
  bool have_recovery_motion_ = false;
  std::shared_ptr<map::KeyFrame> reference_;
  std::shared_ptr<map::KeyFrame> last_keyframe_;
  uint64_t frames_since_keyframe_ = 0;
  int last_inliers_ = 0;
  std::vector<std::shared_ptr<map::KeyFrame>> local_keyframes_;
  std::vector<std::shared_ptr<map::MapPoint>> local_points_;
  std::vector<FramePose> frame_poses_;
  // The last tracked frames and their poses, oldest first, for the moving-keypoint check
  // (MovingKeypointsOptions::frame_gap of them; cleared when tracking is lost).
  std::deque<std::pair<feature::Frame, geometry::SE3>> recent_frames_;
  const KeyFrameDatabase* database_ = nullptr;
  StaticScores static_scores_;
  YoungPointCheck young_points_;
  // Per keypoint of the current frame: the chi-square error of its match after the last pose
  // optimization (0 when unmatched).
  std::vector<double> current_chi2_;
  uint64_t judged_frames_ = 0;
  // Frames since the last relocalization (ORB-SLAM2's mnLastRelocFrameId); "never" at start.
  uint64_t frames_since_relocalization_ = UINT64_MAX / 2;
  // Monocular initialization: the reference frame and where its keypoints were last matched.
  std::unique_ptr<feature::Frame> init_reference_;
  std::vector<Eigen::Vector2f> init_prev_matched_;
  int rejected_initializations_ = 0;
};

}  // namespace moslam::slam
