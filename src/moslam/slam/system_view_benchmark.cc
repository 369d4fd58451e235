// What slam::System::View costs the tracking thread while a browser watches (issue 26), with the
// page's keyframe graph on against off, on the map of a real run: w_xyz seed 3 (the demo's
// sequence, people walking in an office; MOSLAM_BENCH_FRAMES frames, 300 by default), tracked
// deterministically with the generator's masks before the timing starts. The depth the page can
// ask for costs System::View nothing (the frame's depth image is shared, not copied); it is
// encoded in the viewer's server thread (bench_viewer's BM_EncodeSnapshot/depth:1).
// bench_slam --benchmark_filter=SystemView
#include <cstdlib>
#include <memory>
#include <string>

#include <benchmark/benchmark.h>

#include "moslam/slam/run_dataset.h"
#include "moslam/slam/system.h"
#include "moslam/synth/generator.h"
#include "moslam/testing/shared_data.h"

namespace moslam::slam {
namespace {

// The system after the run, kept for every benchmark of this program.
struct RunSystem {
  testing::TempDir dir;
  std::unique_ptr<System> system;
  MapSummary summary;
  RunSystem() {
    const char* frames_env = std::getenv("MOSLAM_BENCH_FRAMES");
    const int frames = frames_env ? std::atoi(frames_env) : 300;
    synth::GeneratorOptions generator;
    generator.preset = "w_xyz";
    generator.seed = 3;
    generator.frames = frames;
    generator.out = dir.path();
    generator.progress = false;
    synth::GenerateSequence(generator);
    const io::Sequence sequence = io::ReadDataset(dir.path());
    SystemOptions options;
    options.sensor = sequence.sensor;
    options.settings = io::LoadOrbSlamSettings(dir.path() + "/settings.yaml", sequence.sensor);
    options.deterministic = true;
    system = std::make_unique<System>(options);
    for (const io::FrameEntry& entry : sequence.frames) {
      system->Track(LoadFrameInput(entry, options, "moving"));
    }
    // Not finished: a view is taken between two frames of a run, with its tracker's last frame.
    summary = system->Summary();
  }
};

RunSystem& Run() {
  static RunSystem run;
  return run;
}

void BM_SystemView(benchmark::State& state) {
  RunSystem& run = Run();
  ViewRequest request;
  request.graph = state.range(0) != 0;
  SystemView view;
  for (auto _ : state) {
    run.system->View(&view, request);
    benchmark::DoNotOptimize(view.points.data());
  }
  state.counters["keyframes"] = static_cast<double>(run.summary.keyframes);
  state.counters["map_points"] = static_cast<double>(run.summary.map_points);
  state.counters["covisibility"] = static_cast<double>(view.covisibility.size() / 6);
  state.counters["keypoints"] = static_cast<double>(view.keypoint_kinds.size());
}
BENCHMARK(BM_SystemView)->ArgName("graph")->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace moslam::slam
