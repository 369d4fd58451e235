// Speed of `moslam synth` (issue 3 asks for >= 20 frames/s at 640x480 on 2 cores, writing
// included). Run: build/src/moslam/synth/bench_synth
#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/synth/generator.h"
#include "moslam/synth/output_files.h"
#include "moslam/synth/sensor.h"
#include "moslam/testing/shared_data.h"

namespace moslam::synth {
namespace {

const TextureSet& Textures() {
  static const TextureSet set = TextureSet::Procedural(1, 4, 512);
  return set;
}

void BM_ProceduralTextures(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(TextureSet::Procedural(1, 1, 512));
}
BENCHMARK(BM_ProceduralTextures)->Unit(benchmark::kMillisecond);

PeopleStyle Style(const benchmark::State& state) {
  return state.range(0) == 0 ? PeopleStyle::kBoxes : PeopleStyle::kBodies;
}

// Rendering only (GL draw + read-back of colour, depth and ids). Arg: people as boxes (0) or
// skinned bodies (1; posing and skinning included).
void BM_RenderOnly(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures(), 0, 0, Style(state));
  Renderer renderer(640, 480, Textures());
  RenderOutput out;
  int i = 0;
  for (auto _ : state) {
    const double t = (i++ % 300) / 30.0;
    renderer.Render(spec.world.BoxesAt(t), spec.world.MeshesAt(t), spec.camera,
                    spec.T_world_cam(t).Inverse(), spec.lighting, &out);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderOnly)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// A full frame: render, sensor noise, labels (no files). Arg as BM_RenderOnly.
void BM_RenderFrame(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures(), 0, 0, Style(state));
  Renderer renderer(640, 480, Textures());
  GeneratorOptions options;
  int i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(RenderFrame(spec, renderer, i++ % 300, options));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderFrame)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime();

// Posing and skinning one walking body (gait.h, body.h).
void BM_PoseAndSkinBody(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures(), 0, 0, PeopleStyle::kBodies);
  int i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(spec.world.MeshesAt((i++ % 300) / 30.0));
  state.counters["bodies"] = static_cast<double>(spec.world.actors.size());
}
BENCHMARK(BM_PoseAndSkinBody)->Unit(benchmark::kMicrosecond);

// Render and write: the whole `moslam synth` pipeline (writer thread, PNG level 1) for 60 frames.
void BM_RenderAndWrite(benchmark::State& state) {
  testing::TempDir dir;
  GeneratorOptions options;
  options.preset = "w_xyz";
  options.out = dir.path();
  options.frames = 60;
  options.progress = false;
  for (auto _ : state) benchmark::DoNotOptimize(GenerateSequence(options));
  state.SetItemsProcessed(state.iterations() * options.frames);
}
BENCHMARK(BM_RenderAndWrite)
    ->Unit(benchmark::kMillisecond)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Iterations(1);

// Sensor noise alone (colour and Kinect depth) on a rendered frame.
void BM_SensorNoise(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures());
  Renderer renderer(640, 480, Textures());
  RenderOutput out;
  renderer.Render(spec.world.BoxesAt(0), spec.camera, spec.T_world_cam(0).Inverse(), spec.lighting,
                  &out);
  uint64_t frame = 0;
  for (auto _ : state) {
    cv::Mat rgb = out.rgb.clone();
    AddColourNoise(&rgb, {}, 1, frame);
    benchmark::DoNotOptimize(KinectDepth(out.depth, {}, 5000.0, 1, frame++));
  }
}
BENCHMARK(BM_SensorNoise)->Unit(benchmark::kMillisecond);

// PNG encoding at compression level 1 (what the writer thread does). Args: image (0 rgb, 1 depth,
// 2 class, 3 instance, 4 moving), zlib strategy (0 default, 2 Huffman only, 3 RLE).
void BM_EncodePngs(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures());
  Renderer renderer(640, 480, Textures());
  const FrameData f = RenderFrame(spec, renderer, 60, GeneratorOptions());
  const std::vector<int> params = {cv::IMWRITE_PNG_COMPRESSION, 1, cv::IMWRITE_PNG_STRATEGY,
                                   static_cast<int>(state.range(1))};
  const cv::Mat* images[] = {&f.rgb, &f.depth, &f.class_id, &f.instance, &f.moving};
  size_t bytes = 0;
  for (auto _ : state) {
    std::vector<uchar> buf;
    cv::imencode(".png", *images[state.range(0)], buf, params);
    bytes = buf.size();
  }
  state.counters["kB"] = static_cast<double>(bytes) / 1000.0;
}
BENCHMARK(BM_EncodePngs)->Unit(benchmark::kMillisecond)->ArgsProduct({{0, 1, 2, 3, 4}, {0, 2, 3}});

}  // namespace
}  // namespace moslam::synth
