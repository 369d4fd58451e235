#include "moslam/viewer/live_viewer.h"

#include <algorithm>
#include <utility>

#include <spdlog/spdlog.h>

namespace moslam::viewer {
namespace {

using Clock = std::chrono::steady_clock;

// How long a paused run sleeps between looks at the stop flag: a signal handler can set an atomic
// but cannot notify a condition variable, so SIGINT during a pause is seen at this interval.
constexpr auto kStopCheck = std::chrono::milliseconds(200);

void AppendPosition(const geometry::SE3& T_world_cam, std::vector<float>* out) {
  const Eigen::Vector3d& t = T_world_cam.translation();
  out->insert(out->end(),
              {static_cast<float>(t.x()), static_cast<float>(t.y()), static_cast<float>(t.z())});
}

}  // namespace

LiveViewer::LiveViewer(const ViewerOptions& options, const std::atomic<int>* stop)
    : stop_(stop), pause_at_(options.pause_at), paused_(options.start_paused) {
  options.Check();
  server_ =
      std::make_unique<Server>(options.server, [this](const nlohmann::json& c) { OnCommand(c); });
  server_->Post([this] { BroadcastStatus(); });
  spdlog::info(
      "viewer: {} (pause, step and resume there{})", server_->url(),
      options.start_paused ? "; the run stops after its first frame until the page resumes" : "");
}

LiveViewer::~LiveViewer() {
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    finished_ = true;
  }
  control_changed_.notify_all();
  server_->Stop();
}

void LiveViewer::SetGroundTruth(eval::Trajectory ground_truth) {
  if (!ground_truth.has_timestamps()) return;  // nothing to match the frames with
  server_->Post([this, gt = std::move(ground_truth)]() mutable { ground_truth_ = std::move(gt); });
}

bool LiveViewer::paused() const {
  std::lock_guard<std::mutex> lock(control_mutex_);
  return paused_;
}

nlohmann::json LiveViewer::Numbers(const runner::FrameRecord& record) {
  const slam::FrameReport& r = record.report;
  const auto now = Clock::now();
  if (frames_ > 0) {
    const double dt = std::chrono::duration<double>(now - last_frame_time_).count();
    // Frames per second smoothed over ~10 frames; a pause would show as a dip, so a gap of more
    // than a second restarts it.
    if (dt > 0 && dt < 1.0) fps_ = fps_ == 0.0 ? 1.0 / dt : 0.9 * fps_ + 0.1 / dt;
  }
  last_frame_time_ = now;
  ++frames_;
  return {{"type", "frame"},
          {"finished", false},
          {"frame", record.index},
          {"frames", frames_},
          {"timestamp", record.timestamp},
          {"state", runner::StateName(r.state)},
          {"relocalized", r.relocalized},
          {"new_keyframe", r.new_keyframe},
          {"fps", fps_},
          {"features", r.num_features},
          {"inliers", r.num_inliers},
          {"keyframes", r.map_keyframes},
          {"map_points", r.map_points},
          {"mask_coverage", record.mask_fraction},
          {"movable_points_erased", r.movable_points_erased},
          {"ms",
           {{"mask", record.mask_ms},
            {"extract", r.times.extract_ms},
            {"track", r.times.track_ms},
            {"local_map", r.times.local_map_ms},
            {"keyframe", r.times.keyframe_ms},
            {"total", r.times.total_ms}}}};
}

void LiveViewer::OnFrame(const runner::FrameRecord& record, const slam::FrameInput& input,
                         runner::Tracker& tracker) {
  // Kept (shared, not copied) for the final picture, which shows the last frame.
  last_image_ = input.image;
  last_mask_ = input.mask;
  last_depth_ = input.depth;
  // The tracker keeps what only a viewer shows (the keypoints the mask took away) while a browser
  // is connected, from the next frame on.
  const bool watched = server_->clients() > 0;
  if (watched != watching_) {
    tracker.Watch(watched);
    watching_ = watched;
  }
  Snapshot snapshot;
  snapshot.numbers = Numbers(record);
  last_numbers_ = snapshot.numbers;
  snapshot.T_world_cam = last_T_world_cam_ = record.report.T_world_cam;
  if (snapshot.T_world_cam && !first_pose_)
    first_pose_.emplace(record.timestamp, *snapshot.T_world_cam);
  snapshot.first_pose = first_pose_;
  if (snapshot.T_world_cam) AppendPosition(*snapshot.T_world_cam, &pending_trajectory_);
  PauseAtFrame(static_cast<size_t>(record.index));
  // A paused run shows the frame it stopped at, whatever the server has not sent yet, also to a
  // browser that connects later (the server keeps the last picture for it).
  if ((watched && slot_.Empty()) || paused()) {
    Fill(input, tracker, &snapshot);
    Publish(std::move(snapshot), false);
  }
  WaitWhilePaused(input, tracker);
}

void LiveViewer::PauseAtFrame(size_t index) {
  if (!pause_at_ || index < *pause_at_) return;
  pause_at_.reset();  // once: a step or a resume goes on from here
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    paused_ = true;
  }
  spdlog::info("viewer: paused at frame {} (--viewer-pause-at); resume or step on the page", index);
  // Every page shows Resume then, as after its own Pause.
  server_->Post([this] { BroadcastStatus(); });
}

void LiveViewer::Fill(const slam::FrameInput& input, runner::Tracker& tracker, Snapshot* snapshot) {
  slam::ViewRequest request;
  bool depth = false;
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    request.graph = graph_;
    depth = depth_;
  }
  slam::SystemView view;
  if (tracker.View(&view, request)) snapshot->view = std::move(view);
  snapshot->image = input.image;  // shared: the loop never writes a tracked frame's images
  snapshot->mask = input.mask;
  if (depth) snapshot->depth = input.depth;
  snapshot->new_trajectory = std::move(pending_trajectory_);
  pending_trajectory_.clear();
}

void LiveViewer::WaitWhilePaused(const slam::FrameInput& input, runner::Tracker& tracker) {
  std::unique_lock<std::mutex> lock(control_mutex_);
  while (paused_ && steps_ == 0 && !finished_ && !(stop_ != nullptr && stop_->load() != 0)) {
    if (refresh_) {
      refresh_ = false;
      lock.unlock();
      Snapshot snapshot;
      snapshot.numbers = last_numbers_;
      snapshot.T_world_cam = last_T_world_cam_;
      snapshot.first_pose = first_pose_;
      Fill(input, tracker, &snapshot);
      Publish(std::move(snapshot), false);
      lock.lock();
      continue;
    }
    control_changed_.wait_for(lock, kStopCheck);
  }
  if (steps_ > 0) --steps_;
}

void LiveViewer::Finish(const runner::RunResult& result, runner::Tracker& tracker) {
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    finished_ = true;
  }
  control_changed_.notify_all();
  Snapshot snapshot;
  snapshot.numbers = {{"type", "frame"},
                      {"finished", true},
                      {"end", runner::RunEndName(result.end)},
                      {"frames", result.frames.size()},
                      {"keyframes", result.map.keyframes},
                      {"map_points", result.map.map_points},
                      {"wall_s", result.wall_s}};
  if (!result.frames.empty()) {
    const runner::FrameRecord& last = result.frames.back();
    snapshot.numbers["frame"] = last.index;
    snapshot.numbers["timestamp"] = last.timestamp;
    snapshot.numbers["state"] = runner::StateName(last.report.state);
  }
  // The final picture carries the keyframe graph and the depth whatever the page asked, so that
  // they can be turned on after the run; it is sent once.
  slam::ViewRequest request;
  request.graph = true;
  slam::SystemView view;
  if (tracker.View(&view, request)) snapshot.view = std::move(view);
  snapshot.depth = last_depth_;
  // The trajectory after the last corrections (loops), replacing the one drawn while running.
  for (const geometry::SE3& pose : result.camera.poses) {
    AppendPosition(pose, &snapshot.new_trajectory);
  }
  if (!result.camera.poses.empty()) snapshot.T_world_cam = result.camera.poses.back();
  snapshot.image = last_image_;
  snapshot.mask = last_mask_;
  snapshot.first_pose = first_pose_;
  Publish(std::move(snapshot), true);
}

void LiveViewer::Publish(Snapshot snapshot, bool replace) {
  snapshot.numbers["replace_trajectory"] = replace;
  slot_.Put(std::move(snapshot));
  server_->Post([this] { Encode(); });
}

void LiveViewer::Encode() {
  std::optional<Snapshot> snapshot = slot_.Take();
  if (!snapshot) return;  // a later post found it taken already
  if (snapshot->numbers.value("replace_trajectory", false)) picture_.trajectory.clear();
  picture_.trajectory.insert(picture_.trajectory.end(), snapshot->new_trajectory.begin(),
                             snapshot->new_trajectory.end());
  const double timestamp = snapshot->numbers.value("timestamp", 0.0);
  if (snapshot->first_pose) {
    const auto& [t0, T_world_cam0] = *snapshot->first_pose;
    picture_.ground_truth = AlignGroundTruth(ground_truth_, t0, T_world_cam0, timestamp);
  }
  server_->Broadcast(std::make_shared<const std::string>(EncodeSnapshot(*snapshot, picture_)),
                     /*binary=*/true);
}

void LiveViewer::OnCommand(const nlohmann::json& command) {
  const std::string cmd = command["cmd"].get<std::string>();
  // "on" of the toggles; anything but true (missing, not a boolean) turns it off.
  const auto on = command.find("on");
  const bool turn_on = on != command.end() && on->is_boolean() && on->get<bool>();
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    if (cmd == "pause") {
      paused_ = true;
    } else if (cmd == "resume") {
      paused_ = false;
    } else if (cmd == "step") {
      paused_ = true;
      ++steps_;
    } else if (cmd == "graph" || cmd == "depth") {
      bool& toggle = cmd == "graph" ? graph_ : depth_;
      refresh_ = refresh_ || toggle != turn_on;
      toggle = turn_on;
    } else {
      spdlog::debug("viewer: unknown command '{}' ignored", cmd);
      return;
    }
  }
  control_changed_.notify_all();
  BroadcastStatus();
}

void LiveViewer::BroadcastStatus() {
  nlohmann::json status = {{"type", "status"}, {"paused", paused()}};
  {
    std::lock_guard<std::mutex> lock(control_mutex_);
    status["graph"] = graph_;
    status["depth"] = depth_;
  }
  server_->Broadcast(std::make_shared<const std::string>(status.dump()), /*binary=*/false);
}

}  // namespace moslam::viewer
