// What the movable-object mechanisms of issue 24 cost per tracked frame at 640x480 (a body
// covering a fifth of the view, a local map of 2000 points), against the budget of 3 ms: the
// frame's mask (carrying with the motion and depth, structure planes, growth over depth; at full
// size and at the default half scale), the border flags of 1000 keypoints, judging the local
// map's points, the static scores of 400 matched points, the mask regions of 120 inconsistent
// keypoints, the pose optimization with and without weights, the pose consensus of 400 matches,
// the established-points check of 400 matches,
// (per keyframe) the moving-keypoint check, and all of them as one frame runs them
// (BM_MovableAllPerFrame).
// bench_slam
#include <algorithm>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "moslam/feature/movable_mask.h"
#include "moslam/feature/structure_planes.h"
#include "moslam/optim/pose_consensus.h"
#include "moslam/optim/pose_optimizer.h"
#include "moslam/slam/frame_mask.h"
#include "moslam/slam/mask_propagation.h"
#include "moslam/slam/movable_points.h"
#include "moslam/slam/moving_keypoints.h"
#include "moslam/slam/moving_regions.h"
#include "moslam/slam/static_scores.h"
#include "moslam/slam/test_scene.h"
#include "moslam/slam/young_points.h"

namespace moslam::slam {
namespace {

struct Scene {
  cv::Mat depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(3.5f));  // a wall
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8UC1);
  Scene() {
    // The floor 1.2 m below the camera, in front of the wall (the test camera: f = 500,
    // cy = 240), ...
    for (int v = 241; v < 480; ++v) {
      depth.row(v).setTo(std::min(3.5f, static_cast<float>(1.2 * 500.0 / (v - 240))));
    }
    // ... and a body 2 m away over a fifth of the image, partly missed (the lower quarter).
    depth(cv::Rect(250, 60, 160, 380)).setTo(2.0f);
    mask(cv::Rect(250, 60, 160, 290)).setTo(255);
  }
};

// Each mechanism's work on one frame, set up once: the single benchmarks below time one each,
// BM_MovableAllPerFrame all of them as one tracked frame runs them.
// The frame's mask as slam::System makes it (frame_mask.h): the network's mask carried from the
// last frame with the motion and the depth, the structure planes, the growth over depth; at the
// work scale `scale` (1: full size; 2: the default).
struct FrameMaskWork {
  Scene scene;
  FrameMask masks;
  geometry::SE3 motion{Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.005, 0.0, 0.002)};
  explicit FrameMaskWork(int scale = FrameMaskOptions{}.work_scale)
      : masks(testing::TestCamera(), Options(scale)) {}
  static FrameMaskOptions Options(int scale) {
    FrameMaskOptions o;
    o.work_scale = scale;
    return o;
  }
  void Run() {
    benchmark::DoNotOptimize(masks.MaskFor(scene.mask, scene.depth, scene.mask.size(), motion));
    masks.Commit();
  }
};

struct BorderFlagsWork {
  Scene scene;
  std::vector<cv::KeyPoint> keypoints;
  BorderFlagsWork() {
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(0.f, 639.f), v(0.f, 479.f);
    for (int i = 0; i < 1000; ++i) keypoints.emplace_back(u(rng), v(rng), 7.f);
  }
  void Run() const {
    benchmark::DoNotOptimize(feature::KeypointsNearMask(keypoints, scene.mask, 4));
  }
};

// 2000 points on the wall, none erased (the steady state): every one is projected and tested.
struct JudgePointsWork {
  Scene scene;
  map::Map map;
  std::vector<std::shared_ptr<map::MapPoint>> all;
  MovablePointsOptions options;
  JudgePointsWork() {
    testing::Scene points = testing::RandomScene(2000, 2);
    for (auto& p : points.points) p.z() = 3.5;
    const auto kf = testing::ObserveScene(&map, points, geometry::SE3());
    testing::AddSharedPoints(&map, points, {kf}, 0, 2000);
    for (const auto& [id, p] : map.points()) all.push_back(p);
    options.mask_threshold = 1 << 30;  // never erase: measure the same work every iteration
    options.free_space_threshold = 1 << 30;
    options.free_space_evidence = true;  // the most work: both tests on every point
  }
  void Run() {
    const JudgingFrame frame{geometry::SE3(), scene.mask, scene.depth};
    benchmark::DoNotOptimize(JudgeMovablePoints(&map, all, frame, testing::TestCamera(), options));
  }
};

// Once per keyframe: 1000 keypoints with depth looked for in the frame three frames back.
struct MovingKeypointsWork {
  map::Map map;
  testing::Scene scene = testing::RandomScene(1000, 4);
  geometry::SE3 T_earlier = testing::CameraAt(0.0), T_current = testing::CameraAt(0.03);
  feature::Frame earlier = testing::ObserveScene(&map, scene, T_earlier, 40.0)->frame;
  feature::Frame current = testing::ObserveScene(&map, scene, T_current, 40.0)->frame;
  void Run() const {
    benchmark::DoNotOptimize(FindMovingKeypoints(current, T_current, earlier, T_earlier,
                                                 testing::TestCamera(), MovingKeypointsOptions{}));
  }
};

// Per frame: the residuals of 400 matched points update their scores (the tracker's
// JudgeResiduals without the map), a quarter of them moving.
struct StaticScoresWork {
  map::Map map;
  std::vector<std::shared_ptr<map::MapPoint>> points;
  StaticScores scores;
  StaticScoresWork() {
    const testing::Scene scene = testing::RandomScene(400, 5);
    const auto kf = testing::ObserveScene(&map, scene, geometry::SE3());
    for (const auto& x : scene.points) points.push_back(map.CreateMapPoint(x, kf));
  }
  void Run() {
    double sum = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
      sum += scores.Observe(points[i], i % 4 == 0 ? 3.0 : 40.0, optim::kChi2Stereo);
      sum += scores.Weight(points[i]->id) + scores.ShouldCull(points[i]->id);
    }
    benchmark::DoNotOptimize(sum);
  }
};

// 120 inconsistent keypoints: 100 on the body of Scene (one cluster), 20 scattered.
struct MovingRegionsWork {
  Scene scene;
  std::vector<InconsistentKeypoint> keypoints;
  MovingRegionsWork() {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> bu(255.f, 405.f), bv(65.f, 435.f), u(0.f, 639.f),
        v(0.f, 479.f);
    for (int i = 0; i < 100; ++i) keypoints.push_back({cv::Point2f(bu(rng), bv(rng)), 2.0f});
    for (int i = 0; i < 20; ++i) keypoints.push_back({cv::Point2f(u(rng), v(rng)), 3.5f});
  }
  void Run() const {
    benchmark::DoNotOptimize(
        MovingRegions(keypoints, scene.depth, scene.depth.size(), MovingRegionOptions{}));
  }
};

const optim::CameraModel kModel{535.4, 539.2, 320.1, 247.6, 40.0};

// The pose consensus before each stereo/RGB-D pose optimization: 400 matches with depth, a
// quarter of them on something that moved 5 cm.
struct PoseConsensusWork {
  testing::Scene scene = testing::RandomScene(400, 8);
  std::vector<optim::Observation> observations;
  std::vector<Eigen::Vector3d> cam;
  std::vector<double> support;
  PoseConsensusWork() {
    for (size_t i = 0; i < scene.points.size(); ++i) {
      const Eigen::Vector3d x = scene.points[i] + Eigen::Vector3d(i % 4 == 0 ? 0.05 : 0.0, 0, 0);
      optim::Observation o;
      o.pixel = Eigen::Vector2d(kModel.fx * x.x() / x.z() + kModel.cx,
                                kModel.fy * x.y() / x.z() + kModel.cy);
      o.u_right = o.pixel.x() - kModel.bf / x.z();
      observations.push_back(o);
      cam.push_back(x);
      support.push_back(1.0 + (i % 5));
    }
  }
  void Run() const {
    benchmark::DoNotOptimize(optim::FindPoseConsensus(kModel, geometry::SE3(), scene.points,
                                                      observations, cam, {}, support));
  }
};

// The established-points check (young_points.h) of 400 stereo matches, 100 of them young and on an
// object that moved 3 cm sideways: the worst case, the normal equations of both groups and a pose
// optimization without the mover (a frame without movers needs only the normal equations).
struct YoungPointsWork {
  testing::Scene scene = testing::RandomScene(400, 9);
  feature::Frame frame;
  std::vector<size_t> indices;
  std::vector<double> ages;
  YoungPointsWork() {
    frame.scale_factors = {1.0f};
    frame.level_sigma2 = frame.inv_level_sigma2 = {1.0f};
    for (size_t i = 0; i < scene.points.size(); ++i) {
      const bool young = i % 4 == 0;
      const Eigen::Vector3d x = scene.points[i] + Eigen::Vector3d(young ? 0.03 : 0.0, 0, 0);
      const cv::KeyPoint kp(static_cast<float>(kModel.fx * x.x() / x.z() + kModel.cx),
                            static_cast<float>(kModel.fy * x.y() / x.z() + kModel.cy), 31.0f);
      frame.keypoints.push_back(kp);
      frame.keypoints_undistorted.push_back(kp);
      frame.u_right.push_back(static_cast<float>(kp.pt.x - kModel.bf / x.z()));
      frame.depth.push_back(static_cast<float>(x.z()));
      indices.push_back(i);
      ages.push_back(young ? 1.0 : 10.0);
    }
    full.inlier.assign(indices.size(), true);
  }
  YoungPointCheck check{[] {
    YoungPointOptions o;
    o.enabled = true;  // off by default in the system (moslam run --young-points)
    return o;
  }()};
  optim::PoseOptimizerResult full;
  void Run() const {
    benchmark::DoNotOptimize(
        check.Check(kModel, frame, indices, scene.points, ages, full, geometry::SE3()));
  }
};

template <typename Work>
void BM_Work(benchmark::State& state) {
  Work work;
  for (auto _ : state) work.Run();
}

// Arg: the work scale (1: full size, 2: the default).
void BM_MovableFrameMask(benchmark::State& state) {
  FrameMaskWork work(static_cast<int>(state.range(0)));
  for (auto _ : state) work.Run();
}
BENCHMARK(BM_MovableFrameMask)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// The parts of the frame's mask at full size: carrying alone, the structure planes alone.
void BM_MovablePropagation(benchmark::State& state) {
  const Scene scene;
  MaskPropagator propagator(testing::TestCamera(), MaskPropagationOptions{});
  const geometry::SE3 motion(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.005, 0.0, 0.002));
  for (auto _ : state) {
    benchmark::DoNotOptimize(propagator.MaskFor(scene.mask, scene.mask.size(), motion));
    propagator.Commit(scene.depth);
  }
}
BENCHMARK(BM_MovablePropagation)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, BorderFlagsWork)
    ->Name("BM_MovableBorderFlags")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, JudgePointsWork)
    ->Name("BM_MovableJudgePoints")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, MovingKeypointsWork)
    ->Name("BM_MovingKeypoints")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, StaticScoresWork)
    ->Name("BM_StaticScores")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, MovingRegionsWork)
    ->Name("BM_MovingRegions")
    ->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, YoungPointsWork)->Unit(benchmark::kMillisecond);
BENCHMARK_TEMPLATE(BM_Work, PoseConsensusWork)
    ->Name("BM_PoseConsensus")
    ->Unit(benchmark::kMillisecond);

void BM_MovableStructurePlanes(benchmark::State& state) {
  const Scene scene;
  for (auto _ : state) {
    benchmark::DoNotOptimize(feature::StructurePlanes::Find(
        scene.depth, testing::TestCamera(), scene.mask, feature::StructurePlaneOptions{}));
  }
}
BENCHMARK(BM_MovableStructurePlanes)->Unit(benchmark::kMillisecond);

// Every mechanism of issue 24 as one tracked frame of an RGB-D run with a body in view runs them
// (the budget is 3 ms): the frame's mask (propagation, structure planes and completion at the
// default work scale), border flags, judging the
// local map, static scores, the pose consensus and the established-points check twice (at each
// pose optimization; the latter is off by default, moslam run --young-points), the moving
// regions (as if a cluster were found on every frame: the worst case), and the moving-keypoint
// check on every third frame (a keyframe every 2-4 frames in threaded runs). The weights in
// the pose optimization add what BM_PoseWithWeights/1 adds over /0.
void BM_MovableAllPerFrame(benchmark::State& state) {
  FrameMaskWork frame_mask;
  BorderFlagsWork border;
  JudgePointsWork judge;
  StaticScoresWork scores;
  PoseConsensusWork consensus;
  MovingRegionsWork regions;
  MovingKeypointsWork keypoints;
  YoungPointsWork young;
  int frame = 0;
  for (auto _ : state) {
    frame_mask.Run();
    border.Run();
    judge.Run();
    scores.Run();
    consensus.Run();
    consensus.Run();
    young.Run();
    young.Run();
    regions.Run();
    if (frame++ % 3 == 0) keypoints.Run();
  }
}
BENCHMARK(BM_MovableAllPerFrame)->Unit(benchmark::kMillisecond);

// The tracker's pose optimization of 400 stereo matches, unweighted (Arg 0) and with a quarter of
// them weighted down (Arg 1): what the weights add.
void BM_PoseWithWeights(benchmark::State& state) {
  const testing::Scene scene = testing::RandomScene(400, 6);
  const optim::CameraModel& model = kModel;
  std::vector<optim::Observation> observations;
  for (const auto& x : scene.points) {
    optim::Observation o;
    o.pixel = Eigen::Vector2d(model.fx * x.x() / x.z() + model.cx + 0.3,
                              model.fy * x.y() / x.z() + model.cy - 0.2);
    o.u_right = o.pixel.x() - model.bf / x.z();
    observations.push_back(o);
  }
  std::vector<double> weights;
  if (state.range(0) == 1) {
    for (size_t i = 0; i < observations.size(); ++i) weights.push_back(i % 4 == 0 ? 0.1 : 1.0);
  }
  const geometry::SE3 start = testing::CameraAt(0.01);
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        optim::OptimizePose(model, start, scene.points, observations, {}, {}, weights));
  }
}
BENCHMARK(BM_PoseWithWeights)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::slam
