// slam::System (system.h): wires the extractors, the tracker and local mapping. Threads: Track()
// runs in the caller's thread; local mapping runs in one thread fed by a bounded keyframe queue
// (util/bounded_queue.h), or synchronously after each keyframe in deterministic mode. Shared
// state between them is the map (guarded by Map::mutex(), see map/map.h), the queue, an atomic
// "mapping busy" flag, and LocalMapper's timing list (its own mutex).
#include "moslam/slam/system.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "moslam/camera/stereo_camera.h"
#include "moslam/eval/statistics.h"
#include "moslam/feature/frame.h"
#include "moslam/feature/movable_mask.h"
#include "moslam/feature/orb_extractor.h"
#include "moslam/map/map.h"
#include "moslam/mapio/map_file.h"
#include "moslam/slam/frame_mask.h"
#include "moslam/slam/keyframe_database.h"
#include "moslam/slam/local_mapper.h"
#include "moslam/slam/loop_closer.h"
#include "moslam/slam/moving_regions.h"
#include "moslam/slam/system_view.h"
#include "moslam/slam/tracker.h"
#include "moslam/util/bounded_queue.h"
#include "moslam/util/error.h"
#include "moslam/util/thread_priority.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::slam {

const char* ToString(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "not_initialized";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kLost:
      return "lost";
  }
  return "unknown";
}

optim::FarStereo SystemOptions::FarStereoPolicy() const {
  if (far_stereo) return *far_stereo;
  return sensor == io::SensorType::kStereo ? optim::FarStereo::kDepthWeighted
                                           : optim::FarStereo::kFull;
}

void SystemOptions::Check() const {
  if (sensor != io::SensorType::kStereo && sensor != io::SensorType::kRgbD &&
      sensor != io::SensorType::kMonocular) {
    throw InputError("SystemOptions.sensor: only stereo, rgbd and monocular are supported (got " +
                     std::string(io::ToString(sensor)) + ")");
  }
  if (deterministic_mapping_frames < 0) {
    throw InputError("SystemOptions.deterministic_mapping_frames must be >= 0, got " +
                     std::to_string(deterministic_mapping_frames));
  }
  if (!(deterministic_mapping_ms_per_observation >= 0.0)) {
    throw InputError("SystemOptions.deterministic_mapping_ms_per_observation must be >= 0, got " +
                     std::to_string(deterministic_mapping_ms_per_observation));
  }
  if (local_ba_keyframes < 0) {
    throw InputError("SystemOptions.local_ba_keyframes must be >= 0, got " +
                     std::to_string(local_ba_keyframes));
  }
  if (keyframe_queue_capacity < 1) {
    throw InputError("SystemOptions.keyframe_queue_capacity must be >= 1");
  }
  if (mask_margin_px < 0 || mask_propagation_frames < 0 || mask_completion_px < 0) {
    throw InputError(
        "SystemOptions.mask_margin_px, mask_propagation_frames and mask_completion_px must be "
        ">= 0");
  }
  if (mask_work_scale < 1 || mask_work_scale > 4) {
    throw InputError("SystemOptions.mask_work_scale must be in 1..4 (got " +
                     std::to_string(mask_work_scale) + ")");
  }
  if (background_nice < 0 || background_nice > 19) {
    throw InputError("SystemOptions.background_nice must be in 0..19 (got " +
                     std::to_string(background_nice) + ")");
  }
  if (localization && load_map.empty()) {
    throw InputError("SystemOptions.localization needs a map to localize in (load_map)");
  }
  settings.Check(sensor);
}

namespace {

feature::OrbExtractorOptions ExtractorOptions(const io::OrbSlamSettings& settings,
                                              int feature_factor = 1) {
  feature::OrbExtractorOptions options;
  options.ApplySettings(settings.orb);
  options.num_features *= feature_factor;
  return options;
}

cv::Mat ToGrey(const cv::Mat& image, bool rgb) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  if (image.channels() == 3) {
    cv::cvtColor(image, grey, rgb ? cv::COLOR_RGB2GRAY : cv::COLOR_BGR2GRAY);
  } else {
    cv::cvtColor(image, grey, rgb ? cv::COLOR_RGBA2GRAY : cv::COLOR_BGRA2GRAY);
  }
  return grey;
}

// The vocabulary of the options (given, loaded from the path, or none).
std::shared_ptr<const vocab::Vocabulary> LoadVocabulary(const SystemOptions& options) {
  if (options.vocabulary) return options.vocabulary;
  if (options.vocabulary_path.empty()) return nullptr;
  const auto t0 = std::chrono::steady_clock::now();
  auto vocabulary =
      std::make_shared<const vocab::Vocabulary>(vocab::Vocabulary::Load(options.vocabulary_path));
  spdlog::info(
      "vocabulary {}: {} words, k {}, {} levels, loaded in {:.0f} ms", options.vocabulary_path,
      vocabulary->size(), vocabulary->k(), vocabulary->levels(),
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  return vocabulary;
}

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace

class System::Impl : public KeyFrameSink {
 public:
  explicit Impl(const SystemOptions& options)
      : options_((options.Check(), options)),
        camera_(options.settings.camera),
        stereo_camera_(StereoCamera(options)),
        left_extractor_(ExtractorOptions(options.settings)),
        right_extractor_(ExtractorOptions(options.settings)),
        // ORB-SLAM2 extracts twice the features until a monocular map is initialized.
        init_extractor_(ExtractorOptions(options.settings, 2)),
        queue_(static_cast<size_t>(options.keyframe_queue_capacity)),
        mapper_(&map_, camera_, Bf(options), MapperOptions(options)),
        tracker_(&map_, camera_, Bf(options), TrackerOpts(options), this),
        vocabulary_(LoadVocabulary(options)) {
    if (vocabulary_ && !vocabulary_->empty()) {
      keyframe_database_ = std::make_unique<KeyFrameDatabase>(vocabulary_);
      mapper_.SetKeyFrameDatabase(keyframe_database_.get());
      tracker_.SetKeyFrameDatabase(keyframe_database_.get());
      map_.SetKeyFrameEraseListener(
          [db = keyframe_database_.get()](const map::KeyFrame& kf) { db->Erase(kf); });
      if (options_.loop_closing && !options_.localization) {
        loop_closer_ = std::make_unique<LoopCloser>(&map_, camera_, Bf(options),
                                                    keyframe_database_.get(), LoopOptions(options));
      }
    }
    if (!options_.load_map.empty()) LoadMap();
    frame_mask_ = std::make_unique<FrameMask>(camera_, FrameMaskOpts(options_));
    if (!options_.deterministic) mapping_thread_ = std::thread([this] { MappingLoop(); });
    if (!options_.deterministic && loop_closer_) {
      loop_thread_ = std::thread([this] { LoopClosingLoop(); });
    }
  }
  ~Impl() override { Finish(); }

  static bool Mono(const SystemOptions& o) { return o.sensor == io::SensorType::kMonocular; }
  // A monocular settings file may have no baseline: no stereo camera then.
  static std::optional<camera::StereoCamera> StereoCamera(const SystemOptions& o) {
    if (Mono(o)) return std::nullopt;
    return camera::StereoCamera(o.settings.camera, o.settings.bf);
  }
  static double Bf(const SystemOptions& o) { return Mono(o) ? 0.0 : o.settings.bf; }
  static LocalMapperOptions MapperOptions(const SystemOptions& o) {
    LocalMapperOptions m;
    m.monocular = Mono(o);
    m.close_depth = o.settings.CloseDepthMetres();
    m.local_bundle_adjustment = o.local_bundle_adjustment;
    m.far_stereo = o.FarStereoPolicy();
    m.max_local_keyframes = o.local_ba_keyframes;
    return m;
  }
  static LoopCloserOptions LoopOptions(const SystemOptions& o) {
    LoopCloserOptions l;
    l.fix_scale = !Mono(o);  // stereo/RGB-D maps have metric scale; monocular ones drift in scale
    l.global_bundle_adjustment = o.loop_global_bundle_adjustment;
    l.far_stereo = {o.FarStereoPolicy(), o.settings.CloseDepthMetres()};
    l.verify = o.loop_verification;
    if (!o.loop_recent_word_weights) l.recent_word_keyframes = 0;
    // Monocular maps drift in scale as well as in pose: a correction may be a larger share of
    // the path travelled (KITTI 07's monocular run drifts a few per cent, more at turns).
    if (Mono(o)) l.verification.max_drift_ratio = 0.5;
    l.synchronous = o.deterministic;
    return l;
  }
  static TrackerOptions TrackerOpts(const SystemOptions& o) {
    TrackerOptions t;
    t.monocular = Mono(o);
    t.initializer.parallel = !o.deterministic;  // same result either way (fixed seed)
    t.close_depth = o.settings.CloseDepthMetres();
    t.far_stereo = o.FarStereoPolicy();
    t.max_frames_between_keyframes = std::max(1, static_cast<int>(o.settings.fps));
    if (!o.short_loss_recovery) t.recovery_window = 0.0;
    t.movable.mask_evidence = o.movable_evidence;
    t.movable.free_space_evidence = o.free_space_evidence;
    // RGB-D only: stereo depth of far points is too uncertain for its depth test (on KITTI 06
    // it flagged static points and cost a second relocalization in slam/relocalization), and
    // monocular keypoints have none.
    t.moving.enabled = o.moving_keypoint_check && o.sensor == io::SensorType::kRgbD;
    t.static_scores.enabled = o.static_scores;
    t.pose_consensus = o.pose_consensus;
    t.young_points.enabled = o.young_points;
    t.motion_cross_check = o.motion_cross_check;
    t.localization = o.localization;
    return t;
  }

  // Deterministic mode with SystemOptions::deterministic_mapping_frames other than 1 stands in for
  // the mapping thread with a queue on a clock of tracked frames: the keyframe at the front is
  // mapped VirtualMappingFrames() after it reached the front, at the start of the frame then
  // tracked, and the keyframes inserted meanwhile wait behind it. So tracking sees a busy mapper,
  // a queue and a map that lags as a threaded run's does, and local mapping skips what a thread
  // skips while keyframes wait (LocalMapper::ProcessKeyFrame: the neighbour search and the local
  // bundle adjustment) - the two things that make a deterministic run slower than a threaded one.
  bool VirtualQueue() const {
    return options_.deterministic && options_.deterministic_mapping_frames != 1 && !finished_;
  }
  // The frames the keyframe reaching the front of the virtual queue takes: fixed, or (0) by the
  // work of the last local bundle adjustment at the settings' frame rate, at most a second.
  int64_t VirtualMappingFrames() const {
    if (options_.deterministic_mapping_frames > 1) return options_.deterministic_mapping_frames;
    const double fps = std::max(1.0, static_cast<double>(options_.settings.fps));
    const double ms = static_cast<double>(mapper_.LastAdjustmentObservations()) *
                      options_.deterministic_mapping_ms_per_observation;
    const double frames = 1.0 + std::ceil(ms * fps / 1000.0);
    return static_cast<int64_t>(std::min(frames, std::max(2.0, fps)));
  }
  bool MappingIdle() const override {
    if (VirtualQueue()) return virtual_queue_.empty();
    return options_.deterministic || (!mapping_busy_.load() && queue_.size() == 0);
  }
  size_t QueuedKeyFrames() const override {
    // The keyframe being mapped is not in the queue (ORB-SLAM2's mlNewKeyFrames).
    if (VirtualQueue()) return virtual_queue_.empty() ? 0 : virtual_queue_.size() - 1;
    return queue_.size();
  }
  void InterruptMapping() override {
    if (VirtualQueue()) {
      // The running bundle adjustment stops: the keyframe at the front is done next frame.
      if (!virtual_queue_.empty()) {
        virtual_mapped_at_ = std::min(virtual_mapped_at_, frame_index_ + 1);
      }
      return;
    }
    mapper_.InterruptBundleAdjustment();
  }
  void InsertKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe) override {
    if (VirtualQueue()) {
      if (virtual_queue_.empty()) virtual_mapped_at_ = frame_index_ + VirtualMappingFrames();
      virtual_queue_.push_back(keyframe);
      return;
    }
    // Synchronous in deterministic mode, and after Finish() closed the queue (Track() may still
    // be called then; its keyframes are mapped in the caller's thread).
    if (options_.deterministic || !queue_.Push(keyframe)) MapKeyFrame(keyframe, {});
  }
  void MapKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe,
                   const std::function<bool()>& more_queued) {
    mapper_.ProcessKeyFrame(keyframe, more_queued);
    if (loop_closer_) loop_closer_->ProcessKeyFrame(keyframe);
  }
  // The virtual queue's keyframes whose time has come (all of them with `all`), in order.
  void MapDueKeyFrames(bool all) {
    while (!virtual_queue_.empty() && (all || frame_index_ >= virtual_mapped_at_)) {
      const std::shared_ptr<map::KeyFrame> keyframe = virtual_queue_.front();
      virtual_queue_.pop_front();
      MapKeyFrame(keyframe, [this] { return !virtual_queue_.empty(); });
      virtual_mapped_at_ += VirtualMappingFrames();
    }
  }

  FrameReport Track(const FrameInput& input) {
    FrameReport report;
    const auto t0 = std::chrono::steady_clock::now();
    if (VirtualQueue()) MapDueKeyFrames(false);
    const double mapped_ms = MsSince(t0);
    const auto t_mask = std::chrono::steady_clock::now();
    const cv::Mat mask = MaskFor(input);
    report.times.mask_ms = MsSince(t_mask);
    feature::Frame frame = MakeFrame(input, mask);
    if (options_.mask_margin_px > 0 && !mask.empty()) {
      const auto t1 = std::chrono::steady_clock::now();
      frame.near_movable =
          feature::KeypointsNearMask(frame.keypoints, mask, options_.mask_margin_px);
      report.times.mask_ms += MsSince(t1);
    }
    report.num_features = static_cast<int>(frame.size());
    report.times.extract_ms = MsSince(t_mask);
    // Map points are judged by the network's own mask only: carried and completed pixels are
    // good enough to keep the extractor off a body, but they also cover the static surface a
    // body has just left or stands on, at the same depth, and would erase it.
    const TrackOutcome outcome = tracker_.Track(std::move(frame), {input.mask, input.depth});
    report.moving_region_fraction = AddMovingRegions(outcome, input);
    FollowPose(outcome);
    report.movable_points_erased = outcome.movable.erased + outcome.residual_erased;
    movable_points_erased_ += report.movable_points_erased;
    if (outcome.status == TrackStatus::kInitialized) {
      initialized_frame_ = static_cast<int>(frame_index_);
    }
    ++frame_index_;
    report.reason = outcome.reason;
    report.num_matches = outcome.num_matches;
    report.num_inliers = outcome.num_inliers;
    report.new_keyframe = outcome.new_keyframe;
    if (options_.report_keyframe_masks && outcome.new_keyframe) report.keyframe_mask = mask;
    report.relocalized = outcome.relocalized;
    if (outcome.relocalized) ++relocalizations_;
    report.recovered = outcome.recovered;
    if (outcome.recovered) ++recoveries_;
    report.times.track_ms = outcome.track_ms;
    report.times.local_map_ms = outcome.local_map_ms;
    // Deterministic: mapping, synchronous, is counted with the keyframes.
    report.times.keyframe_ms = outcome.keyframe_ms + mapped_ms;
    switch (outcome.status) {
      case TrackStatus::kNotInitialized:
        report.state = TrackingState::kNotInitialized;
        break;
      case TrackStatus::kLost:
        report.state = TrackingState::kLost;
        ++lost_frames_;
        break;
      case TrackStatus::kInitialized:
      case TrackStatus::kOk:
        report.state = TrackingState::kOk;
        report.T_world_cam = outcome.T_cam_world.Inverse();
        break;
    }
    report.map_keyframes = static_cast<int>(map_.num_keyframes());
    report.map_points = static_cast<int>(map_.num_points());
    report.times.total_ms = MsSince(t0);
    return report;
  }

  void Finish() {
    if (VirtualQueue()) MapDueKeyFrames(true);
    finished_ = true;  // keyframes of later Track() calls are mapped at once
    queue_.Close();
    if (mapping_thread_.joinable()) mapping_thread_.join();
    // Mapping has handed over its last keyframe: drain loop closing, then its global BA.
    loop_queue_.Close();
    if (loop_thread_.joinable()) loop_thread_.join();
    if (loop_closer_) loop_closer_->WaitForGlobalBundleAdjustment();
  }

  mapio::MapIdentity Identity() const {
    return mapio::MakeIdentity(options_.sensor, options_.settings, Bf(options_), vocabulary_.get());
  }

  // The map of SystemOptions::load_map, indexed in the keyframe database; the tracker starts
  // lost on it and relocalizes its first frame.
  void LoadMap() {
    if (!keyframe_database_) {
      throw InputError("--load-map " + options_.load_map +
                       ": a saved map needs a vocabulary to relocalize in it (none given)");
    }
    const auto t0 = std::chrono::steady_clock::now();
    mapio::LoadMap(options_.load_map, Identity(), &map_);
    std::lock_guard<std::mutex> lock(map_.mutex());
    for (const auto& [id, kf] : map_.keyframes()) keyframe_database_->Add(kf);
    tracker_.StartFromLoadedMap();
    spdlog::info("map {}: {} keyframes, {} map points, loaded in {:.0f} ms{}", options_.load_map,
                 map_.keyframes().size(), map_.points().size(), MsSince(t0),
                 options_.localization ? " (localization only)" : "");
  }

  void View(SystemView* view, const ViewRequest& request) {
    FillSystemView(map_, tracker_, request, rejected_keypoints_, &view_memory_, view);
  }

  void Watch(bool watched) {
    watched_ = watched;
    for (feature::OrbExtractor* e : {&left_extractor_, &init_extractor_})
      e->set_keep_masked(watched);
    if (!watched) rejected_keypoints_.clear();
  }

  void SaveMap(const std::string& path) {
    Finish();
    const auto t0 = std::chrono::steady_clock::now();
    mapio::SaveMap(map_, Identity(), path);
    std::lock_guard<std::mutex> lock(map_.mutex());
    spdlog::info("map {}: {} keyframes, {} map points, saved in {:.0f} ms", path,
                 map_.keyframes().size(), map_.points().size(), MsSince(t0));
  }

  eval::Trajectory CameraTrajectory() const {
    eval::Trajectory trajectory;
    trajectory.name = "moslam camera trajectory";
    std::lock_guard<std::mutex> lock(map_.mutex());
    for (const auto& fp : tracker_.frame_poses()) {
      if (!fp.reference) continue;
      // Follow erased keyframes up the spanning tree (ORB-SLAM2's SaveTrajectoryTUM).
      geometry::SE3 T_cam_ref = fp.T_cam_ref;
      std::shared_ptr<map::KeyFrame> ref = fp.reference;
      while (ref->bad() && ref->parent()) {
        T_cam_ref = T_cam_ref * ref->T_cam_parent();
        ref = ref->parent();
      }
      trajectory.timestamps.push_back(fp.timestamp);
      trajectory.poses.push_back((T_cam_ref * ref->T_cam_world()).Inverse());
    }
    return trajectory;
  }

  eval::Trajectory KeyFrameTrajectory() const {
    eval::Trajectory trajectory;
    trajectory.name = "moslam keyframe trajectory";
    std::lock_guard<std::mutex> lock(map_.mutex());
    for (const auto& [id, kf] : map_.keyframes()) {
      if (kf->bad()) continue;
      trajectory.timestamps.push_back(kf->frame.timestamp);
      trajectory.poses.push_back(kf->T_world_cam());
    }
    return trajectory;
  }

  std::vector<Eigen::Vector3d> MapPointPositions() const {
    std::vector<Eigen::Vector3d> positions;
    std::lock_guard<std::mutex> lock(map_.mutex());
    positions.reserve(map_.points().size());
    for (const auto& [id, point] : map_.points()) {
      if (!point->bad) positions.push_back(point->position);
    }
    return positions;
  }

  MapSummary Summary() const {
    MapSummary summary;
    {
      std::lock_guard<std::mutex> lock(map_.mutex());
      summary.keyframes = static_cast<int>(map_.keyframes().size());
      summary.map_points = static_cast<int>(map_.points().size());
    }
    summary.lost_frames = lost_frames_;
    summary.relocalizations = relocalizations_;
    summary.recoveries = recoveries_;
    summary.movable_points_erased = movable_points_erased_;
    if (loop_closer_) {
      const LoopCloserStats loops = loop_closer_->Stats();
      summary.loops_closed = loops.loops_closed;
      summary.loops_rejected = loops.loops_rejected;
      summary.global_ba_merged = loops.global_ba_merged;
      summary.loop_times = loops.loop_times;
    }
    summary.initialized_frame = initialized_frame_;
    summary.resets = tracker_.rejected_initializations();
    const std::vector<double> steps = mapper_.StepTimes();
    summary.mapping_steps = static_cast<int>(steps.size());
    summary.local_bundle_adjustments = mapper_.LocalBundleAdjustments();
    for (double ms : steps) summary.mapping_ms_total += ms;
    summary.mapping_ms_median = eval::Median(steps);
    return summary;
  }

 private:
  static FrameMaskOptions FrameMaskOpts(const SystemOptions& o) {
    FrameMaskOptions f;
    f.propagation_frames = o.mask_propagation_frames;
    f.propagation_depth_check = o.mask_propagation_depth_check;
    f.completion_px = o.mask_completion_px;
    f.completion_structure = o.completion_structure;
    f.work_scale = o.mask_work_scale;
    return f;
  }

  // The frame's movable mask: the input's, united with the masks carried from the last frames,
  // and (RGB-D) grown over the depth-connected surface it covers (frame_mask.h).
  cv::Mat MaskFor(const FrameInput& input) {
    if (!input.mask.empty() &&
        (input.mask.type() != CV_8UC1 || input.mask.size() != input.image.size())) {
      throw InputError("FrameInput.mask: expected CV_8UC1 of the image's size " +
                       std::to_string(input.image.cols) + "x" + std::to_string(input.image.rows) +
                       ", got " + std::to_string(input.mask.cols) + "x" +
                       std::to_string(input.mask.rows) + " with " +
                       std::to_string(input.mask.channels()) + " channel(s)");
    }
    return frame_mask_->MaskFor(input.mask, input.depth, input.image.size(), velocity_);
  }

  // Regions around clusters of keypoints the tracker found inconsistent (moving_regions.h),
  // handed to the propagator, which carries them into the next frames; returns the share of the
  // image they cover.
  float AddMovingRegions(const TrackOutcome& outcome, const FrameInput& input) {
    if (!options_.moving_regions || !frame_mask_->carries() || outcome.inconsistent.empty()) {
      return 0.0f;
    }
    const cv::Mat regions =
        MovingRegions(outcome.inconsistent, input.depth, input.image.size(), MovingRegionOptions{});
    if (regions.empty()) return 0.0f;
    frame_mask_->AddRegion(regions);
    return static_cast<float>(cv::countNonZero(regions)) / static_cast<float>(regions.total());
  }

  // The motion the next frame's mask is carried with: the last frame-to-frame velocity.
  void FollowPose(const TrackOutcome& outcome) {
    const bool ok =
        outcome.status == TrackStatus::kOk || outcome.status == TrackStatus::kInitialized;
    if (ok && last_T_cam_world_) {
      velocity_ = outcome.T_cam_world * last_T_cam_world_->Inverse();
    } else {
      velocity_.reset();
    }
    last_T_cam_world_.reset();
    if (ok) last_T_cam_world_ = outcome.T_cam_world;
    frame_mask_->Commit();
  }

  feature::Frame MakeFrame(const FrameInput& input, const cv::Mat& mask) {
    feature::Frame frame = ExtractFrame(input, mask);
    // What the mask took away, for a viewer (Watch): the extractor kept it only while watched.
    if (watched_) {
      const bool init = options_.sensor == io::SensorType::kMonocular && !tracker_.initialized();
      rejected_keypoints_ = (init ? init_extractor_ : left_extractor_).masked_keypoints();
    }
    return frame;
  }

  feature::Frame ExtractFrame(const FrameInput& input, const cv::Mat& mask) {
    const cv::Mat grey = ToGrey(input.image, options_.settings.rgb);
    if (options_.sensor == io::SensorType::kMonocular) {
      feature::OrbExtractor* extractor =
          tracker_.initialized() ? &left_extractor_ : &init_extractor_;
      return feature::MakeMonocularFrame(input.timestamp, grey, mask, extractor, camera_);
    }
    if (options_.sensor == io::SensorType::kStereo) {
      if (input.right.empty())
        throw InputError("FrameInput.right: stereo frame without right image");
      return feature::MakeStereoFrame(input.timestamp, grey,
                                      ToGrey(input.right, options_.settings.rgb), mask,
                                      &left_extractor_, &right_extractor_, *stereo_camera_);
    }
    if (input.depth.empty()) throw InputError("FrameInput.depth: RGB-D frame without depth");
    return feature::MakeRgbdFrame(input.timestamp, grey, input.depth, mask, &left_extractor_,
                                  camera_, options_.settings.bf);
  }

  void LowerPriority(const char* what) const {
    if (!util::LowerCurrentThreadPriority(options_.background_nice)) {
      spdlog::warn("{} thread: could not lower its priority by {}", what, options_.background_nice);
    }
  }

  void MappingLoop() {
    LowerPriority("local mapping");
    while (auto keyframe = queue_.Pop()) {
      mapping_busy_ = true;
      mapper_.ProcessKeyFrame(*keyframe, [this] { return queue_.size() > 0; });
      mapping_busy_ = false;
      // Loop closing after local mapping (ORB-SLAM2's InsertKeyFrame into LoopClosing); blocks
      // when the loop closer is 16 keyframes behind, which only a long correction causes.
      if (loop_closer_ && !loop_queue_.Push(*keyframe)) loop_closer_->ProcessKeyFrame(*keyframe);
    }
  }

  void LoopClosingLoop() {
    LowerPriority("loop closing");
    while (auto keyframe = loop_queue_.Pop()) loop_closer_->ProcessKeyFrame(*keyframe);
  }

  const SystemOptions options_;
  camera::PinholeCamera camera_;
  std::optional<camera::StereoCamera> stereo_camera_;
  feature::OrbExtractor left_extractor_;
  feature::OrbExtractor right_extractor_;
  feature::OrbExtractor init_extractor_;
  map::Map map_;
  BoundedQueue<std::shared_ptr<map::KeyFrame>> queue_;
  LocalMapper mapper_;
  Tracker tracker_;
  // Bag of words (SystemOptions::vocabulary): shared, immutable; null without a vocabulary. The
  // database is guarded by the map mutex (keyframe_database.h).
  std::shared_ptr<const vocab::Vocabulary> vocabulary_;
  std::unique_ptr<KeyFrameDatabase> keyframe_database_;
  std::atomic<bool> mapping_busy_{false};
  std::thread mapping_thread_;
  // Keyframes local mapping has processed, for loop closing (null without a vocabulary or with
  // SystemOptions::loop_closing off). Declared after the database it uses.
  BoundedQueue<std::shared_ptr<map::KeyFrame>> loop_queue_{16};
  std::unique_ptr<LoopCloser> loop_closer_;
  std::thread loop_thread_;
  int lost_frames_ = 0;
  int relocalizations_ = 0;
  int recoveries_ = 0;
  int movable_points_erased_ = 0;
  // The frames' masks (carried between frames, grown over depth), and the poses they are carried
  // with.
  std::unique_ptr<FrameMask> frame_mask_;
  std::optional<geometry::SE3> last_T_cam_world_, velocity_;
  int64_t frame_index_ = 0;
  // Deterministic stand-in for the mapping thread (VirtualQueue()): the keyframes waiting, the
  // first being mapped, and the frame at whose start it is done.
  std::deque<std::shared_ptr<map::KeyFrame>> virtual_queue_;
  int64_t virtual_mapped_at_ = 0;
  bool finished_ = false;
  int initialized_frame_ = -1;
  ViewMemory view_memory_;                       // System::View's, untouched while nobody watches
  bool watched_ = false;                         // System::Watch
  std::vector<cv::Point2f> rejected_keypoints_;  // of the last frame, while watched
};

System::System(const SystemOptions& options) : impl_(std::make_unique<Impl>(options)) {}
System::~System() = default;
FrameReport System::Track(const FrameInput& input) { return impl_->Track(input); }
void System::Finish() { impl_->Finish(); }
eval::Trajectory System::CameraTrajectory() const { return impl_->CameraTrajectory(); }
eval::Trajectory System::KeyFrameTrajectory() const { return impl_->KeyFrameTrajectory(); }
MapSummary System::Summary() const { return impl_->Summary(); }
std::vector<Eigen::Vector3d> System::MapPointPositions() const {
  return impl_->MapPointPositions();
}
void System::SaveMap(const std::string& path) { impl_->SaveMap(path); }
void System::View(SystemView* view, const ViewRequest& request) { impl_->View(view, request); }
void System::Watch(bool watched) { impl_->Watch(watched); }

}  // namespace moslam::slam
