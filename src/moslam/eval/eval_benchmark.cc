// ATE and RPE on a 20,000-pose trajectory: association + alignment + statistics must stay well
// under a second. Run: build/src/moslam/eval/bench_eval
#include <benchmark/benchmark.h>

#include <random>

#include "moslam/eval/ate.h"
#include "moslam/eval/rpe.h"
#include "moslam/eval/test_trajectories.h"
#include "moslam/eval/trajectory_io.h"
#include "moslam/testing/shared_data.h"

namespace moslam::eval {
namespace {

constexpr size_t kPoses = 20000;

// Ground truth at 100 Hz and a noisy estimate whose stamps jitter by up to 1.5 ms.
struct Data {
  Trajectory gt = testing::MakeCurve(kPoses, 0.01, 1000.0, "gt");
  Trajectory est;
  Data() {
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> jitter(-0.003, 0.003);
    std::normal_distribution<double> noise(0.0, 0.01);
    est = testing::Transformed(gt, testing::SomeSim3(1.0));
    est.name = "est";
    for (size_t i = 0; i < est.size(); ++i) {
      est.timestamps[i] += jitter(rng) * 0.5;
      est.poses[i] =
          geometry::SE3(est.poses[i].rotation(),
                        est.Position(i) + Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));
    }
  }
};

const Data& TheData() {
  static const Data data;
  return data;
}

void BM_Ate(benchmark::State& state) {
  const Data& d = TheData();
  const AteOptions options = AteOptions::Defaults(static_cast<Convention>(state.range(0)));
  for (auto _ : state) {
    const AteResult r = ComputeAte(d.gt, d.est, options);
    benchmark::DoNotOptimize(r.translation.stats.rmse);
  }
  state.SetLabel(state.range(0) == 0 ? "tum (greedy, Horn)" : "evo (nearest, Umeyama)");
}
BENCHMARK(BM_Ate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

void BM_Rpe(benchmark::State& state) {
  const Data& d = TheData();
  const Convention convention = static_cast<Convention>(state.range(0));
  RpeOptions options = RpeOptions::Defaults(convention);
  options.delta_unit = static_cast<DeltaUnit>(state.range(1));
  options.alignment = AlignmentMode::kSe3;
  options.max_pairs = 0;  // every pair, no subsampling
  size_t pairs = 0;
  for (auto _ : state) {
    const RpeResult r = ComputeRpe(d.gt, d.est, options);
    pairs = r.translation.stats.count;
    benchmark::DoNotOptimize(r.translation.stats.rmse);
  }
  state.SetLabel(std::string(ConventionName(convention)) + ", delta 1 " +
                 DeltaUnitName(options.delta_unit) + ", " + std::to_string(pairs) + " pairs");
}
BENCHMARK(BM_Rpe)
    ->Args({0, static_cast<int>(DeltaUnit::kSeconds)})
    ->Args({0, static_cast<int>(DeltaUnit::kFrames)})
    ->Args({1, static_cast<int>(DeltaUnit::kFrames)})
    ->Args({1, static_cast<int>(DeltaUnit::kMetres)})
    ->Unit(benchmark::kMillisecond);

void BM_ReadTum(benchmark::State& state) {
  moslam::testing::TempDir dir;
  const std::string path = dir.path() + "/est.txt";
  WriteTum(TheData().est, path);
  for (auto _ : state) benchmark::DoNotOptimize(ReadTum(path).size());
}
BENCHMARK(BM_ReadTum)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::eval
