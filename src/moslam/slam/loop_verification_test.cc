// Each rule of the loop verification on small hand-made maps (slam/test_scene.h): a loop that
// the map agrees with is kept, and one that breaks the rule is refused by that rule.
#include "moslam/slam/loop_verification.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::CameraAt;
using testing::ObserveScene;
using testing::RandomScene;
using testing::Scene;
using testing::TestCamera;

// Only the rule under test.
LoopVerificationOptions Only(const char* rule) {
  LoopVerificationOptions o;
  o.check_drift = std::string(rule) == "drift";
  o.check_revisit = std::string(rule) == "revisit";
  o.check_depth = std::string(rule) == "depth";
  o.check_neighbours = std::string(rule) == "neighbours";
  o.check_spread = std::string(rule) == "spread";
  return o;
}

geometry::SE3 Yawed(const geometry::SE3& T, double degrees) {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(degrees * M_PI / 180.0, Eigen::Vector3d::UnitY()));
  return geometry::SE3(q * T.rotation(), q * T.translation());
}

// Keyframes every 0.5 m along x from 0 to 5 m; the loop links the last one with the first.
struct Walk {
  map::Map map;
  Scene scene = RandomScene(200, 7);
  std::vector<std::shared_ptr<map::KeyFrame>> kfs;
  explicit Walk(double step = 0.5, double bf = 0.0) {
    for (int i = 0; i <= 10; ++i) kfs.push_back(ObserveScene(&map, scene, CameraAt(step * i), bf));
  }
  DetectedLoop Loop(const geometry::SE3& T_cur_world_corrected) {
    DetectedLoop loop;
    loop.current = kfs.back();
    loop.loop = kfs.front();
    loop.S_cur_world = geometry::Sim3(T_cur_world_corrected);
    loop.matched.assign(kfs.back()->points.size(), nullptr);
    return loop;
  }
};

TEST(LoopVerification, PathLengthSumsTheKeyframesOnTheWay) {
  Walk walk;
  double metres = 0.0, degrees = 0.0;
  PathLength(walk.map, walk.kfs.back()->id, walk.kfs.front()->id, &metres, &degrees);
  EXPECT_NEAR(metres, 5.0, 1e-9);
  EXPECT_NEAR(degrees, 0.0, 1e-9);
  PathLength(walk.map, walk.kfs[2]->id, walk.kfs[4]->id, &metres, &degrees);
  EXPECT_NEAR(metres, 1.0, 1e-9);
}

TEST(LoopVerification, DriftBoundKeepsASmallCorrectionAndRefusesAJump) {
  Walk walk;  // 5 m travelled: the bound is 0.3 + 0.1 x 5 = 0.8 m and 10 degrees
  const camera::PinholeCamera camera = TestCamera();
  const LoopVerificationOptions o = Only("drift");
  // Odometry drifted 0.5 m: the loop pulls the camera back by that much.
  LoopVerification v = VerifyLoop(walk.map, walk.Loop(CameraAt(4.5)), camera, 0.0, o);
  EXPECT_TRUE(v.accepted) << v.rejected_by;
  EXPECT_NEAR(v.correction_m, 0.5, 1e-9);
  EXPECT_NEAR(v.path_m, 5.0, 1e-9);
  // The loop claims the camera is back at the start, 5 m from where it drove: no drift explains
  // that (a place that only looks like the start).
  v = VerifyLoop(walk.map, walk.Loop(CameraAt(0.0)), camera, 0.0, o);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "drift");
  EXPECT_NEAR(v.correction_m, 5.0, 1e-9);
  // Turned by 5 degrees: kept; by 25 degrees after driving straight: refused.
  const geometry::SE3 T = walk.kfs.back()->T_cam_world();
  EXPECT_TRUE(VerifyLoop(walk.map, walk.Loop(Yawed(T, 5.0)), camera, 0.0, o).accepted);
  v = VerifyLoop(walk.map, walk.Loop(Yawed(T, 25.0)), camera, 0.0, o);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "rotation");
  EXPECT_NEAR(v.correction_deg, 25.0, 1e-6);
  // The same jump over a longer way is possible drift: 60 m travelled allow 6.3 m.
  Walk far(6.0);
  EXPECT_TRUE(VerifyLoop(far.map, far.Loop(CameraAt(55.0)), camera, 0.0, o).accepted);
}

TEST(LoopVerification, RevisitRuleWantsAReturnNotAKeyframeFurtherOn) {
  const camera::PinholeCamera camera = TestCamera();
  const LoopVerificationOptions o = Only("revisit");
  // Straight on for 5 m: the keyframe 5 m back is no loop, whatever it looks like.
  Walk straight;
  LoopVerification v = VerifyLoop(straight.map, straight.Loop(CameraAt(5.0)), camera, 0.0, o);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "revisit");
  EXPECT_NEAR(v.displacement_m, 5.0, 1e-9);
  // Out 3 m and back to 0.2 m from the start: 5.8 m travelled, a return.
  map::Map map;
  const Scene scene = RandomScene(50, 3);
  std::vector<std::shared_ptr<map::KeyFrame>> kfs;
  for (double x : {0.0, 1.0, 2.0, 3.0, 2.0, 1.0, 0.2}) {
    kfs.push_back(ObserveScene(&map, scene, CameraAt(x)));
  }
  DetectedLoop loop;
  loop.current = kfs.back();
  loop.loop = kfs.front();
  loop.S_cur_world = geometry::Sim3(CameraAt(0.1));
  loop.matched.assign(kfs.back()->points.size(), nullptr);
  v = VerifyLoop(map, loop, camera, 0.0, o);
  EXPECT_TRUE(v.accepted) << v.rejected_by;
  EXPECT_NEAR(v.path_m, 5.8, 1e-9);
}

TEST(LoopVerification, DriftBoundRefusesAScaleJumpOfAMonocularLoop) {
  Walk walk;
  LoopVerificationOptions o = Only("drift");
  DetectedLoop loop = walk.Loop(walk.kfs.back()->T_cam_world());
  const geometry::Sim3 S = loop.S_cur_world;
  loop.S_cur_world = geometry::Sim3(S.rotation(), S.translation() * 1.2, 1.2);
  EXPECT_TRUE(VerifyLoop(walk.map, loop, TestCamera(), 0.0, o).accepted);
  loop.S_cur_world = geometry::Sim3(S.rotation(), S.translation() * 3.0, 3.0);
  const LoopVerification v = VerifyLoop(walk.map, loop, TestCamera(), 0.0, o);
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "scale");
}

TEST(LoopVerification, DepthRuleRefusesPointsAwayFromTheMeasuredDepths) {
  const double bf = 250.0;  // 0.5 m baseline, fx 500
  Walk walk(0.1, bf);
  const camera::PinholeCamera camera = TestCamera();
  const auto& cur = walk.kfs.back();
  DetectedLoop loop = walk.Loop(cur->T_cam_world());
  for (size_t i = 0; i < 100; ++i) {
    loop.matched[i] = walk.map.CreateMapPoint(walk.scene.points[i], walk.kfs.front());
  }
  LoopVerification v = VerifyLoop(walk.map, loop, camera, bf, Only("depth"));
  EXPECT_TRUE(v.accepted) << v.rejected_by;
  EXPECT_EQ(v.depth_samples, 100);
  EXPECT_DOUBLE_EQ(v.depth_consistent, 1.0);
  // The same rays, 40 % farther: every point projects where it did (a 2D match looks right),
  // but none lies where the stereo pair measured it.
  const Eigen::Vector3d c = cur->CameraCenter();
  for (size_t i = 0; i < 100; ++i) {
    loop.matched[i] =
        walk.map.CreateMapPoint(c + 1.4 * (walk.scene.points[i] - c), walk.kfs.front());
  }
  v = VerifyLoop(walk.map, loop, camera, bf, Only("depth"));
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "depth");
  EXPECT_LT(v.depth_consistent, 0.1);
  // Monocular keyframes have no depth to compare: the rule does not apply.
  EXPECT_TRUE(VerifyLoop(walk.map, loop, camera, 0.0, Only("depth")).accepted);
}

TEST(LoopVerification, NeighbourRuleWantsTheLoopSeenFromTheCurrentNeighbours) {
  Walk walk(0.1);  // 1 m of small steps: every keyframe sees every point
  // The current side: points 0-99 shared by the last four keyframes (covisible neighbours). The
  // loop side: points 100-199 seen by the first keyframe only.
  testing::AddSharedPoints(&walk.map, walk.scene,
                           {walk.kfs[7], walk.kfs[8], walk.kfs[9], walk.kfs[10]}, 0, 100);
  for (int k = 7; k <= 10; ++k) walk.kfs[static_cast<size_t>(k)]->UpdateConnections();
  const camera::PinholeCamera camera = TestCamera();
  const auto& cur = walk.kfs.back();
  DetectedLoop loop = walk.Loop(cur->T_cam_world());
  auto loop_side = [&](const Eigen::Vector3d& shift) {
    loop.loop_points.clear();
    for (int i = 100; i < 200; ++i) {
      auto p = walk.map.CreateMapPoint(walk.scene.points[static_cast<size_t>(i)] + shift,
                                       walk.kfs.front());
      walk.kfs.front()->points[static_cast<size_t>(i)] = p;
      p->AddObservation(walk.kfs.front(), i);
      p->ComputeDistinctiveDescriptor();
      p->UpdateNormalAndDepth();
      loop.loop_points.push_back(p);
    }
  };
  loop_side(Eigen::Vector3d::Zero());
  LoopVerification v = VerifyLoop(walk.map, loop, camera, 0.0, Only("neighbours"));
  EXPECT_TRUE(v.accepted) << v.rejected_by;
  EXPECT_EQ(v.neighbours_tried, 3);
  EXPECT_EQ(v.neighbours_passing, 3);
  // A loop side that fits the current keyframe alone (here: 1 m off for everyone, as if the
  // loop's correction were right for one view only) is found from none of the neighbours.
  loop_side(Eigen::Vector3d(1.0, 0.0, 0.0));
  v = VerifyLoop(walk.map, loop, camera, 0.0, Only("neighbours"));
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "neighbours");
  EXPECT_EQ(v.neighbours_passing, 0);
}

TEST(LoopVerification, SpreadRuleRefusesMatchesInOnePatch) {
  Walk walk(0.1);
  const camera::PinholeCamera camera = TestCamera();
  const auto& cur = walk.kfs.back();
  DetectedLoop loop = walk.Loop(cur->T_cam_world());
  const auto point = walk.map.CreateMapPoint(Eigen::Vector3d(0, 0, 7), walk.kfs.front());
  int in_patch = 0;
  for (size_t i = 0; i < cur->points.size(); ++i) {
    const cv::Point2f& pt = cur->frame.keypoints_undistorted[i].pt;
    if (pt.x >= 0 && pt.x < 160 && pt.y >= 0 && pt.y < 120) {
      loop.matched[i] = point;
      ++in_patch;
    }
  }
  ASSERT_GE(in_patch, 2);
  LoopVerification v = VerifyLoop(walk.map, loop, camera, 0.0, Only("spread"));
  EXPECT_FALSE(v.accepted);
  EXPECT_EQ(v.rejected_by, "spread");
  EXPECT_EQ(v.spread_cells, 1);
  for (size_t i = 0; i < cur->points.size(); ++i) loop.matched[i] = point;
  v = VerifyLoop(walk.map, loop, camera, 0.0, Only("spread"));
  EXPECT_TRUE(v.accepted) << v.rejected_by;
  EXPECT_GE(v.spread_cells, 4);
}

TEST(LoopVerification, OptionsAreChecked) {
  LoopVerificationOptions o;
  o.Check();
  o.min_depth_consistent = 1.5;
  EXPECT_THROW(o.Check(), InputError);
  o = LoopVerificationOptions();
  o.min_spread_cells = 17;
  EXPECT_THROW(o.Check(), InputError);
  o = LoopVerificationOptions();
  o.max_drift_ratio = -0.1;
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace moslam::slam
