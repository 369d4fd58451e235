#include "moslam/slam/movable_points.h"

#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::AddSharedPoints;
using testing::CameraAt;
using testing::ObserveScene;
using testing::TestCamera;

// Four points 2 m in front of the camera at the origin: left, centre, right and far right
// (u = 195, 320, 445, 570 at fx = 500), observed by `num_keyframes` keyframes.
struct Fixture {
  map::Map map;
  testing::Scene scene;
  std::vector<std::shared_ptr<map::MapPoint>> points;

  explicit Fixture(int num_keyframes) {
    scene = testing::RandomScene(4, 3);
    scene.points = {{-0.5, 0.0, 2.0}, {0.0, 0.0, 2.0}, {0.5, 0.0, 2.0}, {1.0, 0.0, 2.0}};
    std::vector<std::shared_ptr<map::KeyFrame>> kfs;
    for (int k = 0; k < num_keyframes; ++k) {
      kfs.push_back(ObserveScene(&map, scene, CameraAt(0.01 * k)));
    }
    AddSharedPoints(&map, scene, kfs, 0, 4);
    for (const auto& [id, p] : map.points()) points.push_back(p);
  }
};

// A frame at the origin; depth `background` everywhere (0: no depth image), the mask over the
// column band [u0, u1) with depth `mask_depth` there.
JudgingFrame Frame(double background, int u0, int u1, double mask_depth) {
  JudgingFrame f;
  f.mask = cv::Mat::zeros(480, 640, CV_8UC1);
  f.mask.colRange(u0, u1).setTo(255);
  if (background > 0.0) {
    f.depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(background));
    f.depth.colRange(u0, u1).setTo(mask_depth);
  }
  return f;
}

// `times` frames of judging; the stats of the last.
MovablePointsStats Judge(Fixture* fx, const JudgingFrame& frame,
                         const MovablePointsOptions& options, int times = 1) {
  MovablePointsStats stats;
  for (int k = 0; k < times; ++k) {
    stats = JudgeMovablePoints(&fx->map, fx->points, frame, TestCamera(), options);
  }
  return stats;
}

MovablePointsOptions WithFreeSpace() {
  MovablePointsOptions options;
  options.free_space_evidence = true;
  return options;
}

TEST(MovablePoints, APointSeenInLaterMasksIsErased) {
  Fixture fx(2);
  MovablePointsOptions options;  // two frames of mask evidence erase
  // The centre point (u = 320) lies in a body's mask, at the body's depth.
  const JudgingFrame frame = Frame(2.0, 300, 340, 2.0);
  MovablePointsStats stats = Judge(&fx, frame, options);
  EXPECT_EQ(stats.mask_hits, 1);
  EXPECT_EQ(stats.erased, 0);
  stats = Judge(&fx, frame, options);
  EXPECT_EQ(stats.erased, 1);
  EXPECT_TRUE(fx.points[1]->bad);
  EXPECT_EQ(fx.map.points().size(), 3u);
  for (int i : {0, 2, 3}) EXPECT_FALSE(fx.points[i]->bad);
  // Switched off: nothing is judged.
  options.mask_evidence = false;
  options.free_space_evidence = false;
  Fixture off(2);
  Judge(&off, frame, options, 5);
  EXPECT_EQ(off.map.points().size(), 4u);
}

TEST(MovablePoints, AStaticPointBehindAPassingBodyIsKept) {
  Fixture fx(2);
  // A body 1 m in front of the centre point covers it: nearer depth there, so no evidence.
  const JudgingFrame frame = Frame(2.0, 300, 340, 1.0);
  for (int k = 0; k < 5; ++k) {
    const MovablePointsStats stats = Judge(&fx, frame, WithFreeSpace());
    EXPECT_EQ(stats.mask_hits, 0);
    EXPECT_EQ(stats.erased, 0);
  }
  EXPECT_EQ(fx.map.points().size(), 4u);
}

TEST(MovablePoints, FreeSpaceWhereAPointShouldBeErasesIt) {
  Fixture fx(2);
  // No mask; the right half of the image (u >= 400: the points at u = 445 and 570) sees a wall
  // at 4 m where the points claim 2 m (a body that walked away); the left half agrees (2 m).
  JudgingFrame frame;
  frame.depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(2.02));
  frame.depth.colRange(400, 640).setTo(4.0);
  const MovablePointsOptions options = WithFreeSpace();  // three frames erase
  for (int k = 0; k < 2; ++k) EXPECT_EQ(Judge(&fx, frame, options).erased, 0);
  const MovablePointsStats stats = Judge(&fx, frame, options);
  EXPECT_EQ(stats.free_space_hits, 2);
  EXPECT_EQ(stats.erased, 2);
  EXPECT_FALSE(fx.points[0]->bad);
  EXPECT_FALSE(fx.points[1]->bad);
  EXPECT_TRUE(fx.points[2]->bad);
  EXPECT_TRUE(fx.points[3]->bad);
  // At a depth edge (the window reaches the near surface) a point is not judged: the point at
  // u = 195 with the edge 1 px to its right.
  Fixture edge(2);
  frame.depth.setTo(2.02);
  frame.depth.colRange(196, 640).setTo(4.0);
  Judge(&edge, frame, options, 5);
  EXPECT_FALSE(edge.points[0]->bad);
}

TEST(MovablePoints, WithoutDepthOnlyYoungPointsAreJudged) {
  MovablePointsOptions options;
  options.max_observations_without_depth = 4;
  const JudgingFrame frame = Frame(0.0, 300, 340, 0.0);
  Fixture young(2);  // two observations
  Judge(&young, frame, options, 2);
  EXPECT_TRUE(young.points[1]->bad);
  Fixture old(6);  // six observations: a static point that a body passes in front of
  Judge(&old, frame, options, 5);
  EXPECT_FALSE(old.points[1]->bad);
}

TEST(MovablePoints, OptionsAreChecked) {
  MovablePointsOptions options;
  options.mask_threshold = 0;
  EXPECT_THROW(options.Check(), InputError);
  options = {};
  options.depth_rel = -1.0;
  EXPECT_THROW(options.Check(), InputError);
}

}  // namespace
}  // namespace moslam::slam
