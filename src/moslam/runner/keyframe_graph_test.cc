// keyframe_graph.json: what `moslam run` writes of the final keyframe graph reads back as the
// view held it, and a broken file is an error naming it rather than a wrong picture.
#include "moslam/runner/keyframe_graph.h"

#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

using ::testing::HasSubstr;

// A tracker whose view is a fixed three-keyframe graph with one loop.
class GraphTracker : public Tracker {
 public:
  slam::FrameReport Track(const slam::FrameInput&) override { return {}; }
  void Finish() override {}
  eval::Trajectory CameraTrajectory() const override { return {}; }
  eval::Trajectory KeyFrameTrajectory() const override { return {}; }
  slam::MapSummary Summary() const override { return {}; }
  bool View(slam::SystemView* view, const slam::ViewRequest& request) override {
    view->keyframes.resize(3);
    view->loops = {0, 2};
    view->has_graph = request.graph;
    if (request.graph) {
      view->covisibility = {0, 1, 150, 1, 0, 150, 1, 2, 120, 2, 1, 120};
      view->spanning_tree = {1, 0, 2, 1};
    }
    return true;
  }
};

eval::Trajectory Keyframes(size_t n) {
  eval::Trajectory t;
  for (size_t k = 0; k < n; ++k) {
    t.timestamps.push_back(100.0 + 0.5 * static_cast<double>(k));
    t.poses.emplace_back();
  }
  return t;
}

TEST(KeyFrameGraphFile, TheTrackersFinalGraphReadsBackAsItsViewHeldIt) {
  GraphTracker tracker;
  const auto graph = FinalKeyFrameGraph(tracker, Keyframes(3));
  ASSERT_TRUE(graph.has_value());
  EXPECT_EQ(graph->covisibility.size(), 12u);
  // Keyframes other than the view's: edges would point at the wrong ones, so none.
  EXPECT_FALSE(FinalKeyFrameGraph(tracker, Keyframes(4)).has_value());

  const testing::TempDir dir;
  const std::string path = dir.path() + "/keyframe_graph.json";
  WriteKeyFrameGraph(*graph, path);
  const KeyFrameGraph read = ReadKeyFrameGraph(path);
  EXPECT_EQ(read.timestamps, graph->timestamps);
  EXPECT_EQ(read.covisibility, graph->covisibility);  // written once each, read both ways
  EXPECT_EQ(read.spanning_tree, graph->spanning_tree);
  EXPECT_EQ(read.loops, graph->loops);
}

TEST(KeyFrameGraphFile, ABrokenFileIsAnErrorNamingIt) {
  const testing::TempDir dir;
  const std::string path = dir.path() + "/keyframe_graph.json";
  const auto read_back = [&](const std::string& text) {
    std::ofstream(path) << text;
    return testing::ErrorOf([&] { ReadKeyFrameGraph(path); });
  };
  const std::string head = R"({"format": "moslam keyframe graph", "version": 1, )";
  EXPECT_THAT(testing::ErrorOf([&] { ReadKeyFrameGraph(dir.path() + "/none.json"); }),
              HasSubstr("cannot be read"));
  EXPECT_THAT(read_back("[1, 2"), HasSubstr("not a keyframe graph"));
  EXPECT_THAT(read_back(R"({"format": "moslam keyframe graph", "version": 7})"),
              HasSubstr("version 7"));
  EXPECT_THAT(read_back(head + R"("timestamps": [1, 2]})"), HasSubstr("covisibility"));
  const std::string edges = R"("covisibility": [[0, 1, 120]], "spanning_tree": [[1, 0]], )";
  EXPECT_THAT(read_back(head + R"("timestamps": [1, 2], )" + edges + R"("loops": [[0, 2]]})"),
              HasSubstr("\"loops\": keyframe 2 of 2"));
  EXPECT_THAT(read_back(head + R"("timestamps": [1, 2], )" + edges + R"("loops": [[0]]})"),
              HasSubstr("is not 2 numbers"));
  EXPECT_THAT(read_back(head + R"("timestamps": [1, 2], )" + edges + R"("loops": [["a", 1]]})"),
              HasSubstr(path));
}

}  // namespace
}  // namespace moslam::runner
