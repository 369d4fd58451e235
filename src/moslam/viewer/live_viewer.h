// The live viewer of `moslam run --viewer` (docs/RUNNING.md): a runner::FrameObserver that
// hands each frame's picture to the viewer's server (server.h) and pauses the run loop on the
// page's command.
//
// Threads: OnFrame runs in the tracking thread. It records the numbers and the camera position
// (always; a few bytes), and, only while a browser is connected and the server has encoded the
// previous picture, asks the tracker for a copy of the map (runner::Tracker::View) and puts it
// with the frame's images (shared, not copied) into a latest-value slot (latest_slot.h). The
// server thread takes it, encodes it (JPEG/PNG, arrays) and sends it; a browser that reads slowly
// is skipped (ServerOptions::max_buffered_bytes). Tracking never waits for the server or for a
// browser; it waits only while the page has paused the run.
//
// What the page shows on demand is asked for with commands and applies to every browser: "graph"
// (covisibility and spanning-tree edges, slam::ViewRequest) and "depth" (the depth image), each
// {"cmd": ..., "on": true|false}. The tracker is told whether anyone watches
// (runner::Tracker::Watch: the keypoints the mask took away are kept only then).
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "moslam/eval/trajectory.h"
#include "moslam/runner/run_loop.h"
#include "moslam/viewer/latest_slot.h"
#include "moslam/viewer/message.h"
#include "moslam/viewer/server.h"

namespace moslam::viewer {

struct ViewerOptions {
  ServerOptions server;
  bool start_paused = false;  // the run stops after its first frame until the page resumes/steps
  // The run stops at the first frame whose index (FrameRecord::index) is at least this, as if the
  // page had pressed Pause as it was shown (moslam run --viewer-pause-at): a frame to look at,
  // and a pause that a test can rely on whatever the machine's load, since the run cannot end
  // before it, unlike a click that may arrive late.
  std::optional<size_t> pause_at;
  void Check() const { server.Check(); }
};

class LiveViewer : public runner::FrameObserver {
 public:
  // Starts the server (InputError when it cannot listen). `stop` (RunOptions::stop, may be null):
  // a paused run also ends when it is set.
  LiveViewer(const ViewerOptions& options, const std::atomic<int>* stop);
  ~LiveViewer() override;

  // The data set's ground truth, drawn beside the trajectory once the first frame is tracked
  // (aligned to its pose). Before the run.
  void SetGroundTruth(eval::Trajectory ground_truth);
  void OnFrame(const runner::FrameRecord& record, const slam::FrameInput& input,
               runner::Tracker& tracker) override;
  // After the run (the tracker finished): the final map and trajectory, marked finished; the
  // page keeps showing them. Unpauses nothing: the loop is over.
  void Finish(const runner::RunResult& result, runner::Tracker& tracker);

  // Keeps serving the last picture until SIGINT or SIGTERM (Server::WaitForStopSignal).
  int WaitForStopSignal() { return server_->WaitForStopSignal(); }
  std::string url() const { return server_->url(); }
  const Server& server() const { return *server_; }
  bool paused() const;

 private:
  nlohmann::json Numbers(const runner::FrameRecord& record);
  // Pauses the run at ViewerOptions::pause_at once `index` reaches it (tracking thread).
  void PauseAtFrame(size_t index);
  // The map's copy (as the page asks for it) and the frame's images into *snapshot.
  void Fill(const slam::FrameInput& input, runner::Tracker& tracker, Snapshot* snapshot);
  void Publish(Snapshot snapshot, bool replace);
  void Encode();                                  // server thread
  void OnCommand(const nlohmann::json& command);  // server thread
  void BroadcastStatus();                         // server thread
  // Tracking thread: blocks while paused; a toggle meanwhile publishes the frame again with
  // what the page now asks for.
  void WaitWhilePaused(const slam::FrameInput& input, runner::Tracker& tracker);

  const std::atomic<int>* stop_;
  LatestSlot<Snapshot> slot_;
  // Tracking thread only.
  std::vector<float> pending_trajectory_;
  size_t frames_ = 0;
  double fps_ = 0.0;
  std::chrono::steady_clock::time_point last_frame_time_;
  cv::Mat last_image_, last_mask_, last_depth_;
  nlohmann::json last_numbers_;  // of the last frame, to publish it again
  std::optional<geometry::SE3> last_T_world_cam_;
  std::optional<std::pair<double, geometry::SE3>> first_pose_;  // of the first tracked frame
  bool watching_ = false;           // what the tracker was last told (Tracker::Watch)
  std::optional<size_t> pause_at_;  // ViewerOptions::pause_at, until it is reached
  // Server thread only.
  RunPicture picture_;
  eval::Trajectory ground_truth_;
  // Pause / step, set by the server thread, waited on by the tracking thread.
  mutable std::mutex control_mutex_;
  std::condition_variable control_changed_;
  bool paused_ = false;
  int steps_ = 0;
  bool finished_ = false;
  // What the page asks for beyond the default picture (commands "graph", "depth"), and whether a
  // paused frame should be published again because that changed.
  bool graph_ = false;
  bool depth_ = false;
  bool refresh_ = false;
  std::unique_ptr<Server> server_;  // last: stopped first, before what its thread uses
};

}  // namespace moslam::viewer
