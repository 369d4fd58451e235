// The SLAM system facade (ORB-SLAM2's System, Mur-Artal & Tardós 2017), the one entry point apps
// use: frames in, per-frame reports out, trajectories at the end. Behind it: tracking in the
// caller's thread and local mapping in its own thread, fed through a bounded keyframe queue
// (docs/ARCHITECTURE.md, "Threads and data flow"). With `deterministic` set, mapping runs
// synchronously after each new keyframe and every seed is fixed, so runs are identical.
//
//   slam::System system(options);                 // throws InputError on a bad settings file
//   for (...) { slam::FrameReport r = system.Track(input); ... }
//   system.Finish();                              // drains mapping, stops threads
//   eval::Trajectory trajectory = system.CameraTrajectory();
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/eval/trajectory.h"
#include "moslam/geometry/se3.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/io/sequence.h"
#include "moslam/optim/observation.h"

namespace moslam::vocab {
class Vocabulary;
}  // namespace moslam::vocab

namespace moslam::slam {

struct SystemOptions {
  io::SensorType sensor = io::SensorType::kRgbD;  // stereo, RGB-D or monocular
  io::OrbSlamSettings settings;                   // as loaded by io::LoadOrbSlamSettings
  // Mapping synchronously after each keyframe, fixed seeds, one thread everywhere.
  bool deterministic = false;
  int keyframe_queue_capacity = 8;  // bounded queue tracking -> local mapping (keyframes)
  // Deterministic mode only: how local mapping is timed (issue 28). 1 (default): each keyframe is
  // mapped at once, so mapping is never busy, tracking makes a keyframe whenever it would like
  // one and every keyframe runs its local bundle adjustment: 1-2.6x slower than a threaded run on
  // the walking presets (w_xyz the slowest). Otherwise a stand-in for the mapping thread: keyframes
  // wait in a queue on a clock of tracked frames and are mapped at the start of the frame their
  // time comes in, so tracking sees a busy mapper (ORB-SLAM2's AcceptKeyFrames is false while it
  // maps, and tracking then inserts a keyframe only when it must: slam/tracker.cc, NeedNewKeyFrame)
  // and a map that lags, and the keyframes mapped while others wait skip the neighbour search and
  // the local bundle adjustment, as a thread does. A keyframe takes this many frames (>= 2), or
  // with 0 as long as its thread would on the data set's clock (settings' Camera.fps): 1 + the
  // observations of the last local bundle adjustment x deterministic_mapping_ms_per_observation, in
  // frames, at most a second's (mapping's work, counted without a clock: the same on every machine;
  // 0.06 ms matches the keyframe counts of threaded runs since the local BA left Ceres, 0.12
  // before). On the RGB-D walking presets 0 makes as many keyframes as threaded runs at 0.75-1.05x
  // their speed, KITTI 06 stereo at 0.8x; on monocular KITTI 07 the map then lags too far, as in a
  // threaded run (docs/RUNNING.md, "Deterministic runs"); and the tests and docs/EVALUATION.md
  // measure the best case of a mapping thread, which is why 1 stays the default.
  int deterministic_mapping_frames = 1;
  double deterministic_mapping_ms_per_observation = 0.06;
  // Nice increment (0-19) of the local-mapping and loop-closing threads (and the global bundle
  // adjustments they start). Local mapping keeps a core busy refining the map whenever it can;
  // on a 2-core machine that also runs a segmentation network it would take its share from
  // tracking and segmentation, which set the frame rate. Lowered, it uses what they leave. 0
  // keeps every thread at the process's priority (ORB-SLAM2's behaviour). Linux only.
  int background_nice = 0;
  // Local bundle adjustment after each keyframe (LocalMapperOptions::local_bundle_adjustment);
  // off only for experiments that measure what it contributes.
  bool local_bundle_adjustment = true;
  // How tracking, local and global bundle adjustment weigh the disparity of stereo observations
  // beyond ThDepth (optim::FarStereo; LocalMapperOptions::far_stereo, TrackerOptions::far_stereo,
  // LoopCloserOptions::far_stereo). Unset: kDepthWeighted for stereo, whose far disparities are
  // biased on real images (issue 29, docs/EVALUATION.md "Stereo disparity bias"), kFull (as
  // ORB-SLAM2) for RGB-D, where no such bias was measured and every result stays as it was.
  std::optional<optim::FarStereo> far_stereo;
  optim::FarStereo FarStereoPolicy() const;
  // LocalMapperOptions::max_local_keyframes (0: every covisible keyframe, as ORB-SLAM2).
  int local_ba_keyframes = 0;
  // Bag-of-words vocabulary (vocab::Vocabulary::Load: this project's binary format or
  // ORB-SLAM2's ORBvoc.txt), loaded once at construction; it enables the keyframe database and
  // relocalization (loop closing uses it too). Empty: no vocabulary, no relocalization (a lost
  // tracker keeps trying its reference keyframe).
  std::string vocabulary_path;
  // An already loaded (or trained) vocabulary; takes precedence over vocabulary_path. Shared, so
  // several systems or tests load it once.
  std::shared_ptr<const vocab::Vocabulary> vocabulary;
  // Loop closing (slam/loop_closer.h) in its own thread, fed by local mapping; needs a vocabulary
  // (without one it is off whatever this says). Default on, as ORB-SLAM2; off to measure what it
  // contributes (moslam run --no-loop-closing).
  bool loop_closing = true;
  // The full bundle adjustment after each closed loop
  // (LoopCloserOptions::global_bundle_adjustment).
  bool loop_global_bundle_adjustment = true;
  // Loops are checked against the map before they move it (slam/loop_verification.h: drift
  // bound, depths, neighbours, spread); off closes every loop ORB-SLAM2's tests accept (moslam
  // run --no-loop-verification).
  bool loop_verification = true;
  // Loop detection down-weights the words of recently passed places (repeated structure;
  // LoopCloserOptions::recent_word_keyframes); off: ORB-SLAM2's BoW scores (moslam run
  // --no-loop-word-weights).
  bool loop_recent_word_weights = true;
  // Short-loss recovery (TrackerOptions::recovery_window, slam/tracker_recovery.cc): for 2 s
  // after the last tracked frame a lost frame is searched at the constant-velocity prediction and
  // a relocalization must land near it. Off: ORB-SLAM2's relocalization, which takes any place
  // that matches (moslam run --no-short-loss-recovery).
  bool short_loss_recovery = true;
  // Movable objects beyond the per-frame mask (issue 24; docs/EVALUATION.md measures each):
  // map points seen inside later frames' masks are erased (slam/movable_points.h) ...
  bool movable_evidence = true;
  // ... and, RGB-D, those where the measured depth shows free space (no mask needed). Off by
  // default: it also erases the many static points at depth edges, whose depth is the
  // background's or the foreground's by chance, and with exact masks that cost 2-3x in ATE
  // (docs/EVALUATION.md, "Imperfect masks");
  bool free_space_evidence = false;
  // RGB-D: keyframe keypoints seen moving against a frame 3 frames back seed no map point
  // (slam/moving_keypoints.h; not for stereo, whose far depths are too uncertain for it);
  bool moving_keypoint_check = true;
  // no new map point within this many pixels of a mask (0: off);
  int mask_margin_px = 4;
  // masks carried into the next frames with the predicted motion (slam/mask_propagation.h),
  // so a frame the network missed, or did not run on, still has one; 0 frames: off;
  int mask_propagation_frames = 3;
  // ... RGB-D: dropping the carried pixels behind which the new depth shows the body has left
  // (MaskPropagationOptions::depth_check; moslam run --no-propagation-depth-check);
  bool mask_propagation_depth_check = true;
  // RGB-D: masks grown over the depth-connected surface they cover, up to this many pixels
  // (feature::CompleteMaskByDepth), so a body the network saw only in part (its head, its legs)
  // is masked whole; 0: off ...
  int mask_completion_px = 400;
  // ... never onto the large planes of the frame's depth (floor, walls: feature::StructurePlanes),
  // which the feet touch; without this, growth is bounded by mask_completion_px alone (moslam run
  // --no-completion-planes; ablations).
  bool completion_structure = true;
  // The carrying and the growth run on images downsampled by this factor (1..4; slam/frame_mask.h:
  // 2 cuts their cost ~4x, the network's pixels stay exact; moslam run --mask-work-scale).
  int mask_work_scale = 2;
  // Geometry for what no network knows (issue 24): each map point's static probability from its
  // residuals across frames weights pose optimization, and points judged moving are erased
  // (slam/static_scores.h; moslam run --no-static-scores) ...
  bool static_scores = true;
  // ... and clusters of keypoints found inconsistent with the camera's motion become mask
  // regions carried into the next frames like a network's (slam/moving_regions.h; needs
  // mask_propagation_frames > 0; moslam run --no-moving-regions).
  bool moving_regions = true;
  // Stereo / RGB-D: the matches that agree on each frame's pose are found by counting before it is
  // optimized (optim/pose_consensus.h), so a close moving object cannot take the camera along
  // (moslam run --no-pose-consensus).
  bool pose_consensus = true;
  // Stereo / RGB-D: young map points that fit a pose of their own much better than the one the
  // long-known points give are left out of the frame's pose and judged moving
  // (slam/young_points.h; moslam run --young-points). Off by default: measured on the
  // unknown mover and a static scene only (docs/EVALUATION.md, "Young points").
  bool young_points = false;
  // A motion model that keeps few of the last frame's inliers is cross-checked with the
  // reference keyframe (TrackerOptions::motion_cross_check; moslam run --no-motion-cross-check).
  bool motion_cross_check = true;
  // A map saved by an earlier run (System::SaveMap, docs/MAP_FORMAT.md) to start from: the first
  // frames are relocalized in it (a vocabulary is required), then tracking and, without
  // `localization`, mapping continue on it. Empty: start a new map. A file made with another
  // sensor, camera or vocabulary, or damaged, is an InputError naming it (moslam run --load-map).
  std::string load_map;
  // ORB-SLAM2's localization mode on the loaded map: frames are tracked against it and
  // relocalized when lost, but no keyframe or map point is added or erased and loop closing is
  // off, so the map stays as loaded (moslam run --localization). Needs load_map.
  bool localization = false;
  // Each new keyframe's report carries the movable mask its features were extracted with
  // (FrameReport::keyframe_mask), so that the keyframes' depth can later be fused without the
  // movable objects (moslam run --save-keyframe-masks, moslam map export). Off: nothing is kept.
  bool report_keyframe_masks = false;
  void Check() const;  // InputError naming the field
};

// One frame as the tracker takes it. Images are already loaded (io::LoadFrameImages).
struct FrameInput {
  double timestamp = 0.0;  // seconds
  cv::Mat image;           // left (stereo), colour (RGB-D) or the (monocular) image: CV_8UC1, or
                           // CV_8UC3/CV_8UC4 converted to grey following settings.rgb
  cv::Mat right;           // stereo: the rectified right image, same size and type
  cv::Mat depth;           // RGB-D: CV_32FC1 metres registered to `image` (0 = invalid)
  cv::Mat mask;            // CV_8UC1 of the image's size, non-zero = movable object; empty = none
};

enum class TrackingState { kNotInitialized, kOk, kLost };
const char* ToString(TrackingState state);  // "not_initialized", "ok", "lost"

// Wall-clock milliseconds spent in each stage of Track() for this frame.
struct StageTimes {
  double extract_ms = 0.0;    // ORB extraction (+ stereo matching / depth lookup)
  double track_ms = 0.0;      // motion model / reference keyframe tracking
  double local_map_ms = 0.0;  // local map tracking incl. pose optimization
  double keyframe_ms = 0.0;   // keyframe decision and creation (and, deterministic, mapping)
  double mask_ms = 0.0;       // mask propagation, completion and border flags (in extract_ms)
  double total_ms = 0.0;
};

struct FrameReport {
  TrackingState state = TrackingState::kNotInitialized;
  std::string reason;    // why not ok ("too few matches with the motion model", ...)
  int num_features = 0;  // keypoints extracted
  int num_matches = 0;   // matches from motion-model / reference-keyframe tracking
  int num_inliers = 0;   // map points tracked after local-map pose optimization
  bool new_keyframe = false;
  bool relocalized = false;  // the pose came from relocalization after tracking was lost
  bool recovered = false;    // lost before, tracked again from the predicted pose (short loss)
  // map points this frame's mask, depth or residuals showed to be movable
  int movable_points_erased = 0;
  float moving_region_fraction = 0.0f;  // share of the image the geometric regions cover
  StageTimes times;
  std::optional<geometry::SE3> T_world_cam;  // when tracking is ok (or just initialized)
  // The map's size after this frame (erased keyframes and points are gone from it): over a long
  // run, whether the map levels off once the place is mapped (frames.csv, docs/ROBUSTNESS.md).
  int map_keyframes = 0;
  int map_points = 0;
  // On a new keyframe with SystemOptions::report_keyframe_masks: the frame's movable mask as the
  // extractor got it (the network's, united with the carried one and grown over depth; CV_8UC1,
  // non-zero = movable), empty when the frame had none. Shares the tracker's buffer: read-only.
  cv::Mat keyframe_mask;
};

struct MapSummary {
  int keyframes = 0;
  int initialized_frame = -1;  // index of the frame (from 0) whose Track() initialized the map
  int resets = 0;  // monocular: initial maps rejected after bundle adjustment (ORB-SLAM2 resets)
  int map_points = 0;
  int lost_frames = 0;
  int relocalizations = 0;        // frames relocalized (FrameReport::relocalized)
  int recoveries = 0;             // frames recovered after a short loss (FrameReport::recovered)
  int movable_points_erased = 0;  // FrameReport::movable_points_erased, summed
  int loops_closed = 0;           // loop corrections (LoopCloserStats)
  int loops_rejected = 0;         // loops found but refused by the verification
  int global_ba_merged = 0;       // full bundle adjustments after a loop, written back
  // Per closed loop: the timestamps (s) of the current and the loop keyframe, so that a run's
  // summary tells a true loop (a return to an earlier place) from a false one.
  std::vector<std::pair<double, double>> loop_times;
  int mapping_steps = 0;             // keyframes processed by local mapping
  int local_bundle_adjustments = 0;  // of those, the ones that ran a local bundle adjustment
  double mapping_ms_median = 0.0;    // per processed keyframe
  double mapping_ms_total = 0.0;
};

// A viewer's copy of the system after a frame (viewer/, issue 26): plain data, made only when
// System::View is called, so that a run without a viewer pays nothing for it.
enum class ViewPointState : uint8_t {
  kMap = 0,            // in the map
  kLocal = 1,          // in the local map the last frame was tracked against
  kTracked = 2,        // matched by the last frame (an inlier)
  kNew = 3,            // made from one of the two newest keyframes (still on probation)
  kErasedMovable = 4,  // erased after movable-object evidence (a mask or free space showed it)
  kErasedOther = 5,    // erased otherwise: culled, fused, or judged moving by its residuals
};
enum class ViewKeypointKind : uint8_t {
  kUntracked = 0,  // matched no map point
  kTracked = 1,    // matched a map point (an inlier)
  kNearMask = 2,   // next to the movable mask: may track, seeds no point
  kMoving = 3,     // seen moving against an earlier frame
};
// What a viewer asks of System::View beyond the points, keyframes and keypoints.
struct ViewRequest {
  // The keyframe graph: covisibility edges and the spanning tree (SystemView::covisibility,
  // spanning_tree); a few thousand numbers on a long run, so only when the page shows them.
  bool graph = false;
};
struct SystemView {
  std::vector<float> points;          // x, y, z (world, metres) per map point, then the erased ones
  std::vector<uint8_t> point_states;  // ViewPointState per point of `points`
  std::vector<geometry::SE3> keyframes;  // T_world_cam of each keyframe, by id
  std::vector<float> keypoints;          // x, y (pixels) per keypoint of the last frame
  std::vector<uint8_t> keypoint_kinds;   // ViewKeypointKind per keypoint
  // x, y (pixels) of the last frame's keypoints that its movable mask took away (the extractor
  // would have kept them without the mask: feature::OrbExtractor::masked_keypoints); filled only
  // while System::Watch is on, so that the extractor does that work only then.
  std::vector<float> rejected_keypoints;
  // Edges between keyframes, as indices into `keyframes`. The closed loops always (a pair per
  // loop, the loop keyframe first, ordered by the current keyframe: the newest loop last) ...
  std::vector<uint32_t> loops;
  // ... the rest with ViewRequest::graph only (has_graph): i, j, weight per covisibility edge of
  // at least 100 shared map points (what ORB-SLAM2's viewer draws), each pair in both directions,
  // and child, parent per keyframe in the spanning tree (every keyframe but the first).
  bool has_graph = false;
  std::vector<uint32_t> covisibility;
  std::vector<uint32_t> spanning_tree;
};
// Covisibility edges weaker than this are left out of the view (ORB-SLAM2's viewer's threshold).
constexpr int kViewCovisibilityMinWeight = 100;

class System {
 public:
  explicit System(const SystemOptions& options);
  ~System();  // calls Finish() if it was not called
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  FrameReport Track(const FrameInput& input);
  // Waits until local mapping has processed every queued keyframe, then stops its thread.
  void Finish();

  // Every frame that has a pose (ORB-SLAM2 stores each frame relative to its reference keyframe,
  // so the poses follow later keyframe corrections), timestamps in seconds.
  eval::Trajectory CameraTrajectory() const;
  eval::Trajectory KeyFrameTrajectory() const;
  MapSummary Summary() const;
  // The world positions of the map points not erased (api::Slam::MapPoints, the Python module).
  std::vector<Eigen::Vector3d> MapPointPositions() const;
  // Fills *view after the last Track(); call it from the tracking thread (it reads the tracker's
  // scratch state) and only when someone watches. Points erased since the previous call are
  // kept in later views (the newest 20000), with why they went.
  void View(SystemView* view, const ViewRequest& request = {});
  // Whether a viewer watches (tracking thread, between Track calls; off at first). While on, each
  // frame's extraction also keeps the keypoints the movable mask took away, for the next View
  // (SystemView::rejected_keypoints); off, tracking does nothing for a viewer.
  void Watch(bool watched);
  // Finishes (as Finish()) and writes the whole map to `path` (mapio/map_file.h: a temporary file
  // renamed when complete). InputError when it cannot be written.
  void SaveMap(const std::string& path);

 private:
  class Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace moslam::slam
