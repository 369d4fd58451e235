// Speed of pose-only optimization (every tracked frame) and local bundle adjustment (every new
// keyframe) on synthetic scenes of the sizes ORB-SLAM2 meets: 300-1000 stereo observations with
// 20 % outliers; ~10 keyframes (3 fixed), ~2000 points, ~10000 edges.
#include <random>

#include <benchmark/benchmark.h>

#include "moslam/optim/bundle_adjuster.h"
#include "moslam/optim/pose_optimizer.h"
#include "moslam/optim/test_scene.h"

namespace moslam::optim {
namespace {

void BM_OptimizePose(benchmark::State& state) {
  std::mt19937 rng(1);
  const CameraModel camera = test::TestCamera();
  const int n = static_cast<int>(state.range(0));
  const test::PoseScene scene = test::MakePoseScene(rng, camera, n, 1.0, 0.2);
  const geometry::SE3 init =
      test::RandomPerturbation(rng, 0.05, 3.0 * M_PI / 180.0) * scene.T_cam_world;
  int inliers = 0;
  for (auto _ : state) {
    const PoseOptimizerResult result =
        OptimizePose(camera, init, scene.points_world, scene.observations);
    inliers = result.num_inliers;
    benchmark::DoNotOptimize(result);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_OptimizePose)->Arg(300)->Arg(1000)->Unit(benchmark::kMillisecond);

// Arg 0: dense_schur_max_poses (0 = always SPARSE_SCHUR, 40 = DENSE_SCHUR for 7 free poses).
void BM_AdjustBundle(benchmark::State& state) {
  std::mt19937 rng(2);
  const test::BundleScene scene = test::MakeBundleScene(rng, 10, 3, 2000, 0.62, 0.5, 0.05);
  BundleAdjusterOptions options;
  options.dense_schur_max_poses = static_cast<int>(state.range(0));
  int iterations = 0;
  for (auto _ : state) {
    const BundleResult result = AdjustBundle(scene.problem, options);
    iterations = result.iterations;
    benchmark::DoNotOptimize(result);
  }
  state.counters["edges"] = static_cast<double>(scene.problem.edges.size());
  state.counters["iterations"] = iterations;
  state.SetLabel(options.dense_schur_max_poses >= 7 ? "dense_schur" : "sparse_schur");
}
BENCHMARK(BM_AdjustBundle)->Arg(40)->Arg(0)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::optim
