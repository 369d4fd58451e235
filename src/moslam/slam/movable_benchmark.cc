// What the movable-object mechanisms of issue 24 cost per tracked frame at 640x480 (a body
// covering a fifth of the view, a local map of 2000 points), against the budget of 3 ms:
// propagation (the warp with depth, the fade and growth), depth completion (with the structure
// planes of the frame), the border flags of
// 1000 keypoints, judging the local map's points, the static scores of 400 matched points, the
// mask regions of 120 inconsistent keypoints, the pose optimization with and without weights,
// the pose consensus of 400 matches,
// and (per keyframe) the moving-keypoint check.
// bench_slam
#include <algorithm>
#include <random>
#include <vector>

#include <benchmark/benchmark.h>

#include "moslam/feature/movable_mask.h"
#include "moslam/feature/structure_planes.h"
#include "moslam/optim/pose_consensus.h"
#include "moslam/optim/pose_optimizer.h"
#include "moslam/slam/mask_propagation.h"
#include "moslam/slam/movable_points.h"
#include "moslam/slam/moving_keypoints.h"
#include "moslam/slam/moving_regions.h"
#include "moslam/slam/static_scores.h"
#include "moslam/slam/test_scene.h"

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

// Completion as slam::System runs it: the structure planes of the frame, then the growth.
void BM_MovableCompletion(benchmark::State& state) {
  const Scene scene;
  const feature::MaskCompletionOptions options;
  for (auto _ : state) {
    const auto planes = feature::StructurePlanes::Find(
        scene.depth, testing::TestCamera(), scene.mask, feature::StructurePlaneOptions{});
    benchmark::DoNotOptimize(
        feature::CompleteMaskByDepth(scene.mask, scene.depth, options, &planes));
  }
}
BENCHMARK(BM_MovableCompletion)->Unit(benchmark::kMillisecond);

void BM_MovableStructurePlanes(benchmark::State& state) {
  const Scene scene;
  for (auto _ : state) {
    benchmark::DoNotOptimize(feature::StructurePlanes::Find(
        scene.depth, testing::TestCamera(), scene.mask, feature::StructurePlaneOptions{}));
  }
}
BENCHMARK(BM_MovableStructurePlanes)->Unit(benchmark::kMillisecond);

void BM_MovableBorderFlags(benchmark::State& state) {
  const Scene scene;
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> u(0.f, 639.f), v(0.f, 479.f);
  std::vector<cv::KeyPoint> keypoints;
  for (int i = 0; i < 1000; ++i) keypoints.emplace_back(u(rng), v(rng), 7.f);
  for (auto _ : state) {
    benchmark::DoNotOptimize(feature::KeypointsNearMask(keypoints, scene.mask, 4));
  }
}
BENCHMARK(BM_MovableBorderFlags)->Unit(benchmark::kMillisecond);

void BM_MovableJudgePoints(benchmark::State& state) {
  const Scene scene;
  // 2000 points on the wall, none erased (the steady state): every one is projected and tested.
  map::Map map;
  testing::Scene points = testing::RandomScene(2000, 2);
  for (auto& p : points.points) p.z() = 3.5;
  const auto kf = testing::ObserveScene(&map, points, geometry::SE3());
  testing::AddSharedPoints(&map, points, {kf}, 0, 2000);
  std::vector<std::shared_ptr<map::MapPoint>> all;
  for (const auto& [id, p] : map.points()) all.push_back(p);
  MovablePointsOptions options;
  options.mask_threshold = 1 << 30;  // never erase: measure the same work every iteration
  options.free_space_threshold = 1 << 30;
  options.free_space_evidence = true;  // the most work: both tests on every point
  const JudgingFrame frame{geometry::SE3(), scene.mask, scene.depth};
  for (auto _ : state) {
    benchmark::DoNotOptimize(JudgeMovablePoints(&map, all, frame, testing::TestCamera(), options));
  }
}
BENCHMARK(BM_MovableJudgePoints)->Unit(benchmark::kMillisecond);

// Once per keyframe: 1000 keypoints with depth looked for in the frame three frames back.
void BM_MovingKeypoints(benchmark::State& state) {
  map::Map map;
  const testing::Scene scene = testing::RandomScene(1000, 4);
  const geometry::SE3 T_earlier = testing::CameraAt(0.0), T_current = testing::CameraAt(0.03);
  const feature::Frame earlier = testing::ObserveScene(&map, scene, T_earlier, 40.0)->frame;
  const feature::Frame current = testing::ObserveScene(&map, scene, T_current, 40.0)->frame;
  const camera::PinholeCamera camera = testing::TestCamera();
  for (auto _ : state) {
    benchmark::DoNotOptimize(FindMovingKeypoints(current, T_current, earlier, T_earlier, camera,
                                                 MovingKeypointsOptions{}));
  }
}
BENCHMARK(BM_MovingKeypoints)->Unit(benchmark::kMillisecond);

// Per frame: the residuals of 400 matched points update their scores (the tracker's
// JudgeResiduals without the map), a quarter of them moving.
void BM_StaticScores(benchmark::State& state) {
  map::Map map;
  const testing::Scene scene = testing::RandomScene(400, 5);
  const auto kf = testing::ObserveScene(&map, scene, geometry::SE3());
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (const auto& x : scene.points) points.push_back(map.CreateMapPoint(x, kf));
  StaticScores scores;
  for (auto _ : state) {
    double sum = 0.0;
    for (size_t i = 0; i < points.size(); ++i) {
      sum += scores.Observe(points[i], i % 4 == 0 ? 3.0 : 40.0, optim::kChi2Stereo);
      sum += scores.Weight(points[i]->id) + scores.ShouldCull(points[i]->id);
    }
    benchmark::DoNotOptimize(sum);
  }
}
BENCHMARK(BM_StaticScores)->Unit(benchmark::kMillisecond);

// 120 inconsistent keypoints: 100 on the body of Scene (one cluster), 20 scattered.
void BM_MovingRegions(benchmark::State& state) {
  const Scene scene;
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> bu(255.f, 405.f), bv(65.f, 435.f), u(0.f, 639.f),
      v(0.f, 479.f);
  std::vector<InconsistentKeypoint> keypoints;
  for (int i = 0; i < 100; ++i) keypoints.push_back({cv::Point2f(bu(rng), bv(rng)), 2.0f});
  for (int i = 0; i < 20; ++i) keypoints.push_back({cv::Point2f(u(rng), v(rng)), 3.5f});
  for (auto _ : state) {
    benchmark::DoNotOptimize(
        MovingRegions(keypoints, scene.depth, scene.depth.size(), MovingRegionOptions{}));
  }
}
BENCHMARK(BM_MovingRegions)->Unit(benchmark::kMillisecond);

// The tracker's pose optimization of 400 stereo matches, unweighted (Arg 0) and with a quarter of
// them weighted down (Arg 1): what the weights add.
void BM_PoseWithWeights(benchmark::State& state) {
  const testing::Scene scene = testing::RandomScene(400, 6);
  const optim::CameraModel model{535.4, 539.2, 320.1, 247.6, 40.0};
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

// The pose consensus before each stereo/RGB-D pose optimization: 400 matches with depth, a
// quarter of them on something that moved 5 cm.
void BM_PoseConsensus(benchmark::State& state) {
  const testing::Scene scene = testing::RandomScene(400, 8);
  const optim::CameraModel model{535.4, 539.2, 320.1, 247.6, 40.0};
  std::vector<optim::Observation> observations;
  std::vector<Eigen::Vector3d> cam;
  std::vector<double> support;
  for (size_t i = 0; i < scene.points.size(); ++i) {
    const Eigen::Vector3d x = scene.points[i] + Eigen::Vector3d(i % 4 == 0 ? 0.05 : 0.0, 0, 0);
    optim::Observation o;
    o.pixel =
        Eigen::Vector2d(model.fx * x.x() / x.z() + model.cx, model.fy * x.y() / x.z() + model.cy);
    o.u_right = o.pixel.x() - model.bf / x.z();
    observations.push_back(o);
    cam.push_back(x);
    support.push_back(1.0 + (i % 5));
  }
  for (auto _ : state) {
    benchmark::DoNotOptimize(optim::FindPoseConsensus(model, geometry::SE3(), scene.points,
                                                      observations, cam, {}, support));
  }
}
BENCHMARK(BM_PoseConsensus)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::slam
