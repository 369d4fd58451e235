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

// Arg 0: the solver: 0 = the fixed-size Schur solver (schur_lm.h, the default), 1 = Ceres with
// SPARSE_SCHUR, 2 = Ceres with DENSE_SCHUR. Arg 1: poses (the first 3 fixed); 10 with 2000 points
// is a local BA of ORB-SLAM2's size (~10000 edges), 40 with 4000 points one of a small room where
// every keyframe sees the others' points (w_xyz: 60-90 poses, 20000-37000 edges).
void BM_AdjustBundle(benchmark::State& state) {
  std::mt19937 rng(2);
  const int poses = static_cast<int>(state.range(1));
  const test::BundleScene scene =
      test::MakeBundleScene(rng, poses, 3, poses == 10 ? 2000 : 4000, 0.62, 0.5, 0.05);
  BundleAdjusterOptions options;
  options.solver = state.range(0) == 0 ? BundleAdjusterOptions::Solver::kSchurLM
                                       : BundleAdjusterOptions::Solver::kCeres;
  options.dense_schur_max_poses = state.range(0) == 2 ? 1000 : 0;
  int iterations = 0;
  for (auto _ : state) {
    const BundleResult result = AdjustBundle(scene.problem, options);
    iterations = result.iterations;
    benchmark::DoNotOptimize(result);
  }
  state.counters["edges"] = static_cast<double>(scene.problem.edges.size());
  state.counters["iterations"] = iterations;
  state.SetLabel(state.range(0) == 0   ? "schur_lm"
                 : state.range(0) == 1 ? "ceres_sparse_schur"
                                       : "ceres_dense_schur");
}
BENCHMARK(BM_AdjustBundle)->ArgsProduct({{0, 1, 2}, {10, 40}})->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::optim
