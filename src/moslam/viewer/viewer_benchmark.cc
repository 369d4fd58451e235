// What the live viewer costs the tracking thread per frame (issue 26: at most 5 % of tracking's
// per-frame time): LiveViewer::OnFrame with no browser connected, and with one that reads every
// message, on a map of 5000 / 20000 points, 100 keyframes and 1500 keypoints (the fake tracker's
// View() copies prepared arrays, as slam::System::View copies the map's). The encoding and
// sending run in the server thread and are measured apart (BM_EncodeSnapshot): on a machine with
// a core to spare they cost tracking nothing.
#include <benchmark/benchmark.h>

#include "moslam/viewer/fake_tracker.h"
#include "moslam/viewer/live_viewer.h"
#include "moslam/viewer/test_client.h"

namespace moslam::viewer {
namespace {

slam::FrameInput Input() {
  slam::FrameInput input;
  input.image = cv::Mat(480, 640, CV_8UC1);
  cv::randu(input.image, 0, 255);
  input.mask = cv::Mat(480, 640, CV_8UC1, cv::Scalar(0));
  input.mask(cv::Rect(100, 100, 200, 200)).setTo(255);
  return input;
}

runner::FrameRecord Record(int index) {
  runner::FrameRecord record;
  record.index = index;
  record.timestamp = 0.03 * index;
  record.report.state = slam::TrackingState::kOk;
  record.report.T_world_cam = geometry::SE3();
  return record;
}

void BM_OnFrame(benchmark::State& state) {
  const bool client = state.range(0) != 0;
  const size_t points = static_cast<size_t>(state.range(1));
  ViewerOptions options;
  options.server.port = 0;
  LiveViewer viewer(options, nullptr);
  testing::FakeTracker tracker(points, 100, 1500);
  std::unique_ptr<testing::WsClient> browser;
  if (client) {
    browser = std::make_unique<testing::WsClient>(
        "ws://127.0.0.1:" + std::to_string(viewer.server().port()) + "/");
    browser->WaitOpen();
    // The server counts the browser once its handshake is done.
    while (viewer.server().clients() == 0) std::this_thread::yield();
  }
  const slam::FrameInput input = Input();
  int index = 0;
  for (auto _ : state) viewer.OnFrame(Record(index++), input, tracker);
  state.counters["views"] = benchmark::Counter(tracker.views.load());
  state.counters["sent"] = benchmark::Counter(viewer.server().stats().sent.load());
}
BENCHMARK(BM_OnFrame)
    ->ArgNames({"client", "points"})
    ->Args({0, 5000})
    ->Args({1, 5000})
    ->Args({0, 20000})
    ->Args({1, 20000})
    ->Unit(benchmark::kMicrosecond)
    ->UseRealTime();

// With `on_demand`, what the page shows only when asked: the keyframe graph (the fake's chain of
// 100 keyframes) and the frame's 640x480 depth, colour-mapped and encoded at 320 wide.
void BM_EncodeSnapshot(benchmark::State& state) {
  testing::FakeTracker tracker(static_cast<size_t>(state.range(0)), 100, 1500);
  const bool on_demand = state.range(1) != 0;
  Snapshot snapshot;
  slam::SystemView view;
  slam::ViewRequest request;
  request.graph = on_demand;
  tracker.View(&view, request);
  snapshot.view = view;
  const slam::FrameInput input = Input();
  snapshot.image = input.image;
  snapshot.mask = input.mask;
  if (on_demand) {
    // A room's depths: a wall 1-4 m away across the view, a nearer box, a strip without depth.
    snapshot.depth = cv::Mat(480, 640, CV_32FC1);
    for (int c = 0; c < 640; ++c) snapshot.depth.col(c).setTo(1.0f + 3.0f * c / 640.0f);
    snapshot.depth(cv::Rect(300, 150, 160, 200)).setTo(0.8f);
    snapshot.depth(cv::Rect(0, 0, 40, 480)).setTo(0.0f);
  }
  RunPicture picture;
  picture.trajectory.assign(3 * 1000, 0.5f);
  size_t bytes = 0;
  for (auto _ : state) bytes = EncodeSnapshot(snapshot, picture).size();
  state.counters["bytes"] = benchmark::Counter(static_cast<double>(bytes));
}
BENCHMARK(BM_EncodeSnapshot)
    ->ArgNames({"points", "on_demand"})
    ->Args({5000, 0})
    ->Args({5000, 1})
    ->Args({20000, 0})
    ->Args({20000, 1})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace moslam::viewer
