// Speed of the geometry primitives that the evaluator and the optimizers call in inner loops.
#include <random>

#include <benchmark/benchmark.h>

#include "moslam/geometry/alignment.h"
#include "moslam/geometry/test_util.h"

namespace moslam::geometry {
namespace {

void BM_SE3ExpLog(benchmark::State& state) {
  std::mt19937 rng(1);
  const SE3 T = test::RandomSE3(rng);
  for (auto _ : state) benchmark::DoNotOptimize(SE3::Exp(T.Log()));
}
BENCHMARK(BM_SE3ExpLog);

void BM_Sim3ExpLog(benchmark::State& state) {
  std::mt19937 rng(2);
  const Sim3 S = test::RandomSim3(rng);
  for (auto _ : state) benchmark::DoNotOptimize(Sim3::Exp(S.Log()));
}
BENCHMARK(BM_Sim3ExpLog);

void BM_Align(benchmark::State& state) {
  std::mt19937 rng(3);
  const int n = static_cast<int>(state.range(0));
  Eigen::Matrix3Xd source(3, n), target(3, n);
  const SE3 T = test::RandomSE3(rng);
  for (int i = 0; i < n; ++i) {
    source.col(i) = test::RandomVector(rng, 5);
    target.col(i) = T * Eigen::Vector3d(source.col(i));
  }
  const bool horn = state.range(1) == 0;
  for (auto _ : state) {
    if (horn) {
      benchmark::DoNotOptimize(AlignHorn(source, target));
    } else {
      benchmark::DoNotOptimize(AlignUmeyama(source, target, true));
    }
  }
  state.SetLabel(horn ? "horn" : "umeyama+scale");
}
BENCHMARK(BM_Align)->Args({20000, 0})->Args({20000, 1});

}  // namespace
}  // namespace moslam::geometry
