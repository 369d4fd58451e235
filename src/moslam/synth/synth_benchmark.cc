// Speed of `moslam synth` (issue 3 asks for >= 20 frames/s at 640x480 on 2 cores, writing
// included). Run: build/src/moslam/synth/bench_synth
#include <benchmark/benchmark.h>

#include "moslam/synth/generator.h"
#include "moslam/synth/output_files.h"
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

// Rendering only (GL draw + read-back of colour, depth and ids).
void BM_RenderOnly(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures());
  Renderer renderer(640, 480, Textures());
  RenderOutput out;
  int i = 0;
  for (auto _ : state) {
    const double t = (i++ % 300) / 30.0;
    renderer.Render(spec.world.BoxesAt(t), spec.camera, spec.T_world_cam(t).Inverse(),
                    spec.lighting, &out);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderOnly)->Unit(benchmark::kMillisecond)->UseRealTime();

// A full frame: render, sensor noise, labels (no files).
void BM_RenderFrame(benchmark::State& state) {
  const SequenceSpec spec = MakePreset("w_xyz", 1, Textures());
  Renderer renderer(640, 480, Textures());
  GeneratorOptions options;
  int i = 0;
  for (auto _ : state) benchmark::DoNotOptimize(RenderFrame(spec, renderer, i++ % 300, options));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RenderFrame)->Unit(benchmark::kMillisecond)->UseRealTime();

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
BENCHMARK(BM_RenderAndWrite)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace
}  // namespace moslam::synth
