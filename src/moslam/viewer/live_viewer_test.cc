#include "moslam/viewer/live_viewer.h"

#include <atomic>
#include <chrono>
#include <functional>
#include <optional>
#include <thread>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/viewer/fake_tracker.h"
#include "moslam/viewer/test_client.h"

namespace moslam::viewer {
namespace {

using testing::FakeTracker;
using testing::WsClient;

ViewerOptions AnyPort(bool paused = false) {
  ViewerOptions options;
  options.server.port = 0;
  options.start_paused = paused;
  return options;
}

std::string WsUrl(const LiveViewer& viewer) {
  return "ws://127.0.0.1:" + std::to_string(viewer.server().port()) + "/";
}

runner::FrameRecord Record(int index) {
  runner::FrameRecord record;
  record.index = index;
  record.timestamp = 0.1 * index;
  record.report.state = slam::TrackingState::kOk;
  record.report.T_world_cam =
      geometry::SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1 * index, 0, 0));
  record.report.map_points = 40;
  record.report.map_keyframes = 3;
  return record;
}

slam::FrameInput Input() {
  slam::FrameInput input;
  input.image = cv::Mat(48, 64, CV_8UC1, cv::Scalar(100));
  input.mask = cv::Mat(48, 64, CV_8UC1, cv::Scalar(0));
  input.mask(cv::Rect(10, 10, 20, 20)).setTo(255);
  return input;
}

// Input() with a depth image: 1 m to 3 m from left to right, a hole in the middle.
slam::FrameInput InputWithDepth() {
  slam::FrameInput input = Input();
  input.depth = cv::Mat(input.image.size(), CV_32FC1);
  for (int c = 0; c < input.depth.cols; ++c) input.depth.col(c).setTo(1.0f + 2.0f * c / 64);
  input.depth(cv::Rect(30, 20, 4, 4)).setTo(0.0f);
  return input;
}

// Whether a binary message is a frame message for frame `index`.
auto IsFrame(int index) {
  return [index](const WsClient::Message& m) {
    if (!m.binary) return false;
    const auto decoded = DecodeMessage(m.payload);
    return decoded && decoded->header.value("frame", -1) == index;
  };
}

TEST(LiveViewer, WithoutABrowserTheMapIsNeverCopied) {
  LiveViewer viewer(AnyPort(), nullptr);
  FakeTracker tracker(100, 3, 50);
  const slam::FrameInput input = Input();
  for (int i = 0; i < 20; ++i) viewer.OnFrame(Record(i), input, tracker);
  EXPECT_EQ(tracker.views.load(), 0);
  EXPECT_FALSE(tracker.watched);  // nor anything kept for a viewer while tracking
}

TEST(LiveViewer, SendsTheMapImageAndNumbers) {
  LiveViewer viewer(AnyPort(), nullptr);
  FakeTracker tracker(100, 3, 50);
  WsClient client(WsUrl(viewer));
  ASSERT_TRUE(client.WaitOpen());
  ASSERT_TRUE(client.WaitMessages(1));  // the pause state, sent to every new browser
  const slam::FrameInput input = Input();
  eval::Trajectory gt;
  for (int i = 0; i < 30; ++i) {
    gt.timestamps.push_back(0.1 * i);
    gt.poses.push_back(geometry::SE3());
  }
  viewer.SetGroundTruth(gt);
  // Frames until one has reached the browser (the first ones may find no client registered).
  int index = 0;
  while (!client.WaitForMessage(IsFrame(index - 1), std::chrono::milliseconds(50)) && index < 200) {
    viewer.OnFrame(Record(index++), input, tracker);
  }
  std::optional<DecodedMessage> message;
  for (const auto& m : client.messages()) {
    if (IsFrame(index - 1)(m)) message = DecodeMessage(m.payload);
  }
  ASSERT_TRUE(message.has_value());
  EXPECT_EQ(message->header["state"], "ok");
  EXPECT_EQ(message->header["map_points"], 40);
  EXPECT_EQ(message->Section("points")->size(), 100 * 3 * sizeof(float));
  EXPECT_EQ(message->Section("keyframes")->size(), 3 * 12 * sizeof(float));
  EXPECT_EQ(message->Section("keypoint_kinds")->size(), 50u);
  // A connected browser has the tracker keep what the mask took away; the closed loops are
  // always sent, the keyframe graph and the depth only when asked (next test).
  EXPECT_TRUE(tracker.watched);
  ASSERT_NE(message->Section("rejected_keypoints"), nullptr);
  EXPECT_EQ(message->Section("rejected_keypoints")->size(), 5 * 2 * sizeof(float));
  ASSERT_NE(message->Section("loops"), nullptr);
  EXPECT_EQ(message->Section("loops")->size(), 2 * sizeof(uint32_t));
  EXPECT_EQ(message->Section("covisibility"), nullptr);
  EXPECT_EQ(message->Section("spanning_tree"), nullptr);
  EXPECT_EQ(message->Section("depth"), nullptr);
  ASSERT_NE(message->Section("image"), nullptr);
  ASSERT_NE(message->Section("mask"), nullptr);
  EXPECT_EQ(message->Section("trajectory")->size(), static_cast<size_t>(index) * 3 * sizeof(float));
  EXPECT_GT(message->Section("ground_truth")->size(), 0u);

  runner::RunResult result;
  result.frames.push_back(Record(index));
  result.map.keyframes = 3;
  result.map.map_points = 40;
  viewer.Finish(result, tracker);
  ASSERT_TRUE(client.WaitForMessage([](const WsClient::Message& m) {
    const auto decoded = m.binary ? DecodeMessage(m.payload) : std::nullopt;
    return decoded && decoded->header.value("finished", false);
  }));
}

// Frames are fed until the client has a frame message that `match` accepts; returns it.
std::optional<DecodedMessage> FeedUntil(LiveViewer& viewer, testing::FakeTracker& tracker,
                                        const slam::FrameInput& input, WsClient& client, int* index,
                                        const std::function<bool(const DecodedMessage&)>& match) {
  const auto accepts = [&](const WsClient::Message& m) {
    const auto decoded = m.binary ? DecodeMessage(m.payload) : std::nullopt;
    return decoded && decoded->header.value("frame", -1) >= 0 && match(*decoded);
  };
  for (int tries = 0; tries < 200; ++tries) {
    viewer.OnFrame(Record((*index)++), input, tracker);
    if (client.WaitForMessage(accepts, std::chrono::milliseconds(50))) break;
  }
  for (const auto& m : client.messages()) {
    if (accepts(m)) return DecodeMessage(m.payload);
  }
  return std::nullopt;
}

TEST(LiveViewer, TheKeyframeGraphAndTheDepthAreSentOnlyWhileThePageAsks) {
  LiveViewer viewer(AnyPort(), nullptr);
  testing::FakeTracker tracker(100, 4, 50);
  WsClient client(WsUrl(viewer));
  ASSERT_TRUE(client.WaitOpen());
  ASSERT_TRUE(client.WaitMessages(1));
  const slam::FrameInput input = InputWithDepth();
  int index = 0;
  const auto plain = FeedUntil(viewer, tracker, input, client, &index,
                               [](const DecodedMessage& m) { return m.Section("points"); });
  ASSERT_TRUE(plain.has_value());
  EXPECT_EQ(plain->Section("covisibility"), nullptr);
  EXPECT_EQ(plain->Section("spanning_tree"), nullptr);
  EXPECT_EQ(plain->Section("depth"), nullptr);
  EXPECT_FALSE(plain->header.contains("depth_far_m"));

  client.Send(R"({"cmd": "graph", "on": true})");
  client.Send(R"({"cmd": "depth", "on": true})");
  // Every browser hears of the toggles (the page sets its checkboxes from them).
  ASSERT_TRUE(client.WaitForMessage([](const WsClient::Message& m) {
    const auto j = nlohmann::json::parse(m.payload, nullptr, false);
    return !m.binary && j.is_object() && j.value("graph", false) && j.value("depth", false);
  }));
  const auto full = FeedUntil(viewer, tracker, input, client, &index, [](const DecodedMessage& m) {
    return m.Section("covisibility") && m.Section("depth");
  });
  ASSERT_TRUE(full.has_value());
  // The fake's chain of 4 keyframes: 3 covisibility edges (once each, i < j, with their weight)
  // and 3 parents.
  EXPECT_EQ(full->Section("covisibility")->size(), 3 * 3 * sizeof(uint32_t));
  EXPECT_EQ(full->Section("spanning_tree")->size(), 3 * 2 * sizeof(uint32_t));
  // The depth as a picture (no wider than half the image width the page shows, 640 / 2 px: this
  // one is not shrunk), its range in the header.
  const std::string& jpeg = *full->Section("depth");
  const cv::Mat depth =
      cv::imdecode(std::vector<uint8_t>(jpeg.begin(), jpeg.end()), cv::IMREAD_COLOR);
  ASSERT_FALSE(depth.empty());
  EXPECT_EQ(depth.cols, 64);
  EXPECT_GT(full->header.value("depth_far_m", 0.0), 2.5);
  EXPECT_LE(full->header.value("depth_far_m", 0.0), 3.0);

  // Off again (a malformed "on" counts as off): the messages shrink back.
  client.Send(R"({"cmd": "graph", "on": "yes"})");
  client.Send(R"({"cmd": "depth", "on": false})");
  ASSERT_TRUE(client.WaitForMessage([](const WsClient::Message& m) {
    const auto j = nlohmann::json::parse(m.payload, nullptr, false);
    return !m.binary && j.is_object() && j.contains("graph") && !j.value("graph", true) &&
           !j.value("depth", true);
  }));
  const auto again = FeedUntil(viewer, tracker, input, client, &index, [](const DecodedMessage& m) {
    return m.Section("points") && !m.Section("covisibility") && !m.Section("depth");
  });
  EXPECT_TRUE(again.has_value());
}

TEST(LiveViewer, PauseStepAndResumeHoldTheRunLoop) {
  LiveViewer viewer(AnyPort(/*paused=*/true), nullptr);
  FakeTracker tracker(10, 1, 10);
  WsClient client(WsUrl(viewer));
  ASSERT_TRUE(client.WaitOpen());
  ASSERT_TRUE(client.WaitMessages(1));
  const slam::FrameInput input = Input();
  std::atomic<int> done{0};
  std::thread loop([&] {
    for (int i = 0; i < 10; ++i) {
      viewer.OnFrame(Record(i), input, tracker);
      ++done;
    }
  });
  // Paused from the start: frame 0 is shown, and the loop waits after it.
  ASSERT_TRUE(client.WaitForMessage(IsFrame(0)));
  EXPECT_EQ(done.load(), 0);
  client.Send("{\"cmd\": \"step\"}");
  ASSERT_TRUE(client.WaitForMessage(IsFrame(1)));
  EXPECT_TRUE(testing::PollUntil([&] { return done.load() == 1; }));
  EXPECT_FALSE(client.WaitForMessage(IsFrame(2), std::chrono::milliseconds(300)));
  EXPECT_EQ(done.load(), 1);
  EXPECT_TRUE(viewer.paused());
  // Turned on while paused, the keyframe graph comes with the same frame, sent again; the loop
  // stays where it is.
  client.Send(R"({"cmd": "graph", "on": true})");
  ASSERT_TRUE(client.WaitForMessage([](const WsClient::Message& m) {
    const auto decoded = m.binary ? DecodeMessage(m.payload) : std::nullopt;
    return decoded && decoded->header.value("frame", -1) == 1 && decoded->Section("spanning_tree");
  }));
  EXPECT_EQ(done.load(), 1);
  client.Send("{\"cmd\": \"resume\"}");
  loop.join();
  EXPECT_EQ(done.load(), 10);
  EXPECT_FALSE(viewer.paused());
}

// --viewer-pause-at: the run stops at the given frame by itself, so a page (or a test) that looks
// late still finds the run paused there rather than ended; every page hears of the pause, and a
// step or a resume goes on from there without stopping at that frame again.
TEST(LiveViewer, PauseAtAFrameHoldsTheRunThere) {
  ViewerOptions options = AnyPort();
  options.pause_at = 5;
  LiveViewer viewer(options, nullptr);
  FakeTracker tracker(10, 1, 10);
  WsClient client(WsUrl(viewer));
  ASSERT_TRUE(client.WaitOpen());
  ASSERT_TRUE(client.WaitMessages(1));
  const slam::FrameInput input = Input();
  std::atomic<int> done{0};
  std::thread loop([&] {
    for (int i = 0; i < 10; ++i) {
      viewer.OnFrame(Record(i), input, tracker);
      ++done;
    }
  });
  ASSERT_TRUE(client.WaitForMessage(IsFrame(5)));  // the paused frame is always sent
  ASSERT_TRUE(client.WaitForMessage([](const WsClient::Message& m) {
    const auto j = nlohmann::json::parse(m.payload, nullptr, false);
    return !m.binary && j.is_object() && j.value("paused", false);
  }));
  EXPECT_TRUE(viewer.paused());
  EXPECT_EQ(done.load(), 5);  // frames 0-4 went through, frame 5 waits
  client.Send("{\"cmd\": \"step\"}");
  ASSERT_TRUE(client.WaitForMessage(IsFrame(6)));
  EXPECT_TRUE(testing::PollUntil([&] { return done.load() == 6; }));
  EXPECT_TRUE(viewer.paused());
  client.Send("{\"cmd\": \"resume\"}");
  loop.join();
  EXPECT_EQ(done.load(), 10);
  EXPECT_FALSE(viewer.paused());
}

TEST(LiveViewer, AStopSignalEndsAPause) {
  std::atomic<int> stop{0};
  LiveViewer viewer(AnyPort(/*paused=*/true), &stop);
  FakeTracker tracker(10, 1, 10);
  std::thread loop([&] { viewer.OnFrame(Record(0), Input(), tracker); });
  stop = 2;
  loop.join();  // returns within the stop check's interval
  SUCCEED();
}

TEST(LiveViewer, AStalledBrowserDoesNotSlowTracking) {
  LiveViewer viewer(AnyPort(), nullptr);
  FakeTracker tracker(20000, 100, 2000);
  testing::RawSocket stalled(viewer.server().port(), 4096);
  ASSERT_NE(testing::StalledWebSocket(&stalled).find("101"), std::string::npos);
  ASSERT_TRUE(testing::PollUntil([&] { return viewer.server().clients() == 1; }));
  slam::FrameInput input;
  input.image = cv::Mat(480, 640, CV_8UC3);
  cv::randu(input.image, 0, 255);
  double slowest_ms = 0;
  for (int i = 0; i < 100; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    viewer.OnFrame(Record(i), input, tracker);
    slowest_ms = std::max(
        slowest_ms,
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  // Copying a 20000-point view is the most a frame pays; never the sending.
  EXPECT_LT(slowest_ms, 200.0);
  EXPECT_GT(viewer.server().stats().skipped.load() + tracker.views.load(), 0u);
}

}  // namespace
}  // namespace moslam::viewer
