// `moslam view RUN_DIR` on run folders made here: the keyframe graph and the closed loops of a
// finished run reach the page in the sections the live page's final picture uses (so the page's
// code is shared), from the map file, from keyframe_graph.json, or (an older folder) the loops
// alone from summary.json; a graph of other keyframes is left out, a broken one is an error.
#include "moslam/viewer/run_dir.h"

#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "moslam/eval/trajectory.h"
#include "moslam/map/keyframe_graph.h"
#include "moslam/mapio/map_file.h"
#include "moslam/mapio/test_map.h"
#include "moslam/runner/keyframe_graph.h"
#include "moslam/runner/outputs.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::viewer {
namespace {

// A finished run's folder: summary.json (with `loops`), the camera and keyframe trajectories.
void WriteRunFolder(const std::string& dir, size_t keyframes, const nlohmann::json& loops) {
  eval::Trajectory t;
  for (size_t k = 0; k < keyframes; ++k) {
    t.timestamps.push_back(1.5 + 0.25 * static_cast<double>(k));
    t.poses.emplace_back(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.1 * k, 0, 0));
  }
  runner::WriteOrbSlamTum(t, 9, dir + "/CameraTrajectory.txt");
  runner::WriteOrbSlamTum(t, 7, dir + "/KeyFrameTrajectory.txt");
  const nlohmann::json summary = {
      {"frames", keyframes}, {"keyframes", keyframes}, {"loops", loops}};
  std::ofstream(dir + "/summary.json") << summary.dump();
}

// The sections of the message `moslam view` sends, as uint32 arrays.
std::vector<uint32_t> Section(const DecodedMessage& message, const std::string& name) {
  const std::string* bytes = message.Section(name);
  if (bytes == nullptr) return {};
  std::vector<uint32_t> out(bytes->size() / 4);
  std::memcpy(out.data(), bytes->data(), out.size() * 4);
  return out;
}

DecodedMessage Sent(const RunView& run) {
  const auto message = DecodeMessage(EncodeSnapshot(run.snapshot, run.picture));
  EXPECT_TRUE(message.has_value());
  return message.value_or(DecodedMessage{});
}

TEST(RunDir, TheGraphAndLoopsOfKeyframeGraphJsonReachThePage) {
  const testing::TempDir dir;
  WriteRunFolder(dir.path(), 4, nlohmann::json::array());
  runner::KeyFrameGraph graph;
  graph.timestamps = {1.5, 1.75, 2.0, 2.25};
  graph.covisibility = {0, 1, 140, 1, 0, 140, 1, 2, 101, 2, 1, 101};
  graph.spanning_tree = {1, 0, 2, 1, 3, 2};
  graph.loops = {0, 3};
  runner::WriteKeyFrameGraph(graph, dir.path() + "/keyframe_graph.json");

  const RunView run = LoadRunView(dir.path());
  ASSERT_TRUE(run.snapshot.view.has_value());
  EXPECT_EQ(run.graph_from, dir.path() + "/keyframe_graph.json");
  const slam::SystemView& v = *run.snapshot.view;
  EXPECT_EQ(v.keyframes.size(), 4u);
  EXPECT_TRUE(v.has_graph);
  EXPECT_EQ(v.covisibility, graph.covisibility);
  EXPECT_EQ(v.spanning_tree, graph.spanning_tree);
  EXPECT_EQ(v.loops, graph.loops);
  // As the live page gets them: covisibility once each (i < j), the tree, the loop.
  const DecodedMessage sent = Sent(run);
  EXPECT_EQ(Section(sent, "covisibility"), (std::vector<uint32_t>{0, 1, 140, 1, 2, 101}));
  EXPECT_EQ(Section(sent, "spanning_tree"), graph.spanning_tree);
  EXPECT_EQ(Section(sent, "loops"), graph.loops);
  EXPECT_TRUE(sent.header.value("finished", false));

  // A graph of other keyframes (the trajectory rewritten since) would draw wrong edges: left out.
  graph.timestamps.back() = 9.0;
  runner::WriteKeyFrameGraph(graph, dir.path() + "/keyframe_graph.json");
  const RunView other = LoadRunView(dir.path());
  EXPECT_FALSE(other.snapshot.view->has_graph);
  EXPECT_TRUE(other.snapshot.view->loops.empty());
  EXPECT_EQ(other.snapshot.view->keyframes.size(), 4u);
  // A broken one is an error naming it.
  std::ofstream(dir.path() + "/keyframe_graph.json") << "{\"format\": 3";
  try {
    LoadRunView(dir.path());
    ADD_FAILURE() << "a broken keyframe_graph.json was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("keyframe_graph.json"), std::string::npos) << e.what();
  }
}

TEST(RunDir, AnOlderFolderShowsTheLoopsOfItsSummary) {
  const testing::TempDir dir;
  // Two loops, the later one first in the file; one more whose keyframe is not in the folder.
  WriteRunFolder(dir.path(), 5,
                 {{{"time", 2.5}, {"loop_time", 1.75}},
                  {{"time", 2.25}, {"loop_time", 1.5}},
                  {{"time", 7.0}, {"loop_time", 1.5}}});
  const RunView run = LoadRunView(dir.path());
  ASSERT_TRUE(run.snapshot.view.has_value());
  EXPECT_FALSE(run.snapshot.view->has_graph);
  EXPECT_EQ(run.snapshot.view->loops, (std::vector<uint32_t>{0, 3, 1, 4}));  // newest last
  EXPECT_EQ(Section(Sent(run), "loops"), run.snapshot.view->loops);
  EXPECT_TRUE(Sent(run).Section("covisibility") == nullptr);
}

TEST(RunDir, AMapFileGivesTheWholeGraphAsTheLiveViewHasIt) {
  const testing::TempDir dir;
  WriteRunFolder(dir.path(), 2, nlohmann::json::array());
  // A run's map: keyframes along a path, points in three consecutive ones (weights over 100), a
  // loop from the last to the first, an erased keyframe.
  map::Map map;
  mapio::testing::BuildTestMap(8, 600, 7, &map);
  mapio::MapIdentity identity;
  identity.sensor = static_cast<int32_t>(io::SensorType::kRgbD);
  identity.camera = {525.0, 525.0, 319.5, 239.5, 0.0, 0.0, 0.0, 0.0, 0.0, 40.0};
  identity.orb_levels = 8;
  identity.orb_scale_factor = 1.2;
  identity.vocabulary_words = 10000;  // the test map's words are below that
  mapio::SaveMap(map, identity, dir.path() + "/map.map");

  const RunView run = LoadRunView(dir.path());
  EXPECT_EQ(run.map_path, dir.path() + "/map.map");
  ASSERT_TRUE(run.snapshot.view.has_value());
  const slam::SystemView& v = *run.snapshot.view;
  map::IndexedKeyFrameGraph expected;
  {
    std::lock_guard<std::mutex> lock(map.mutex());
    expected = map::IndexKeyFrameGraph(map, true, slam::kViewCovisibilityMinWeight);
  }
  EXPECT_EQ(v.keyframes.size(), 7u);
  EXPECT_TRUE(v.has_graph);
  EXPECT_EQ(v.loops, (std::vector<uint32_t>{0, 6}));
  EXPECT_EQ(v.covisibility, expected.covisibility);
  EXPECT_FALSE(v.covisibility.empty());
  EXPECT_FALSE(v.spanning_tree.empty());
  EXPECT_EQ(v.spanning_tree, expected.spanning_tree);
  EXPECT_EQ(Section(Sent(run), "loops"), v.loops);
}

}  // namespace
}  // namespace moslam::viewer
