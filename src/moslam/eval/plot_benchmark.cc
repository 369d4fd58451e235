// Rendering time of the trajectory figure for a long (20,000-pose) trajectory.
#include <cmath>
#include <string>

#include <benchmark/benchmark.h>

#include "moslam/eval/plot.h"
#include "moslam/eval/plot_figure.h"
#include "moslam/eval/plot_layout.h"
#include "moslam/testing/shared_data.h"

namespace moslam::eval {
namespace {

TrajectoryPlotData Spiral(int n) {
  TrajectoryPlotData data;
  data.title = "benchmark";
  data.error_label = "ATE [m]";
  for (int i = 0; i < n; ++i) {
    const double a = 0.01 * i;
    const Eigen::Vector3d ref(std::cos(a) * (1 + 0.0001 * i), std::sin(a), 0.001 * i);
    const Eigen::Vector3d est = ref + Eigen::Vector3d(0.01 * std::sin(3 * a), 0.0, 0.0);
    data.times.push_back(0.03 * i);
    data.reference.push_back(ref);
    data.estimate.push_back(est);
    data.errors.push_back((est - ref).norm());
  }
  return data;
}

void BM_Layout(benchmark::State& state) {
  const TrajectoryPlotData data = Spiral(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(internal::LayoutTrajectoryPlot(data));
}
BENCHMARK(BM_Layout)->Arg(20000)->Unit(benchmark::kMillisecond);

void BM_WritePlot(benchmark::State& state, const std::string& extension) {
  const TrajectoryPlotData data = Spiral(static_cast<int>(state.range(0)));
  testing::TempDir dir;
  for (auto _ : state) WriteTrajectoryPlot(data, dir.path() + "/plot" + extension);
}
BENCHMARK_CAPTURE(BM_WritePlot, png, std::string(".png"))
    ->Arg(20000)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_WritePlot, svg, std::string(".svg"))
    ->Arg(20000)
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace moslam::eval
