// TorchSegmenter::Run on a 480x360 image (CamVid's size) with 2 intra-op threads, for the default
// NetConfig and larger inputs / deeper backbones. Weights are random (ImageNet-initialized nets
// cost the same); 11 classes as CamVid. Args: input width, input height, last_block, stride,
// decoder block (0: none), ASPP channels (head_channels; decoder_channels is two thirds of it).
//
//   OMP_WAIT_POLICY=passive ./build/src/moslam/net/bench_net_segmenter
//   MOSLAM_BENCH_THREADS=1 ./build/src/moslam/net/bench_net_segmenter
#include <algorithm>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <vector>

#include <ATen/Parallel.h>
#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "moslam/net/torch_segmenter.h"

namespace moslam::net {
namespace {

// Intra-op threads: MOSLAM_BENCH_THREADS, default 2 (the target machine's cores). With 1 thread
// the CPU column is the compute cost even on a busy machine; with 2 on a busy machine, set
// OMP_WAIT_POLICY=passive or the OpenMP barrier spinning dominates the wall time.
int Threads() {
  const char* value = std::getenv("MOSLAM_BENCH_THREADS");
  return value != nullptr ? std::max(1, std::atoi(value)) : 2;
}

void BM_TorchSegmenterRun(benchmark::State& state) {
  NetConfig config;
  config.kind = NetKind::kSegmenter;
  config.classes = {"Sky",    "Building", "Pole", "Road",       "Pavement", "Tree",
                    "Symbol", "Fence",    "Car",  "Pedestrian", "Bicyclist"};
  config.movable = {"Car", "Pedestrian", "Bicyclist"};
  config.input_width = static_cast<int>(state.range(0));
  config.input_height = static_cast<int>(state.range(1));
  config.backbone.last_block = static_cast<int>(state.range(2));
  config.backbone.output_stride = static_cast<int>(state.range(3));
  config.decoder_block = static_cast<int>(state.range(4));
  config.head_channels = static_cast<int>(state.range(5));
  config.decoder_channels = config.head_channels * 2 / 3;
  torch::manual_seed(0);
  at::set_num_threads(Threads());
  TorchSegmenter segmenter{SegmenterNet(config)};
  cv::Mat image(360, 480, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  segmenter.Run(image);  // warm-up: first call allocates
  for (auto _ : state) {
    TorchSegmentation s = segmenter.Run(image);
    benchmark::DoNotOptimize(s.probabilities.data);
  }
  state.SetLabel(std::to_string(config.input_width) + "x" + std::to_string(config.input_height) +
                 " block " + std::to_string(config.backbone.last_block) + " os" +
                 std::to_string(config.backbone.output_stride) +
                 (config.decoder_block > 0 ? " decoder " + std::to_string(config.decoder_block)
                                           : std::string()) +
                 " head " + std::to_string(config.head_channels));
}
BENCHMARK(BM_TorchSegmenterRun)
    ->ArgNames({"w", "h", "block", "os", "dec", "head"})
    ->Args({320, 240, 13, 16, 0, 96})  // the default NetConfig
    ->Args({320, 240, 13, 16, 3, 96})  // with the stride-4 decoder
    ->Args({320, 240, 13, 16, 3, 64})  // the same, narrower
    ->Args({320, 240, 13, 16, 6, 96})  // with a stride-8 decoder
    ->Args({400, 300, 13, 16, 0, 96})  // the person card's input size, the previous network
    ->Args({400, 300, 13, 16, 3, 96})  // the person card's network (decoder on block 3)
    ->Args({480, 360, 13, 16, 0, 96})
    ->Args({480, 360, 13, 16, 3, 96})  // the CamVid card's network at CamVid's own size
    ->Args({480, 360, 13, 16, 6, 96})
    ->Args({320, 240, 17, 16, 0, 96})
    ->Args({480, 360, 17, 16, 0, 96})
    ->Args({320, 240, 13, 8, 0, 96})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// The networks shipped in data/models/ (their own weights and configurations), on an image
// resized to the given input size: what the 30 ms budget at 480x360 is about. Args: model (0
// person, 1 CamVid), input width, input height. Run from the repository root, or set
// MOSLAM_BENCH_MODELS to the folder of the .mnet files; MOSLAM_BENCH_IMAGE names a real image
// to run on (default: 480x360 noise; measured the same, 2026-12-01, no denormal slowdown).
void BM_ShippedModel(benchmark::State& state) {
  const char* folder = std::getenv("MOSLAM_BENCH_MODELS");
  const std::string name = state.range(0) == 0 ? "weak_synth_person.mnet" : "weak_camvid.mnet";
  const std::string path = std::string(folder != nullptr ? folder : "data/models") + "/" + name;
  std::unique_ptr<TorchSegmenter> segmenter;
  try {
    segmenter = std::make_unique<TorchSegmenter>(path, Threads());
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  segmenter->set_input_size({static_cast<int>(state.range(1)), static_cast<int>(state.range(2))});
  const char* image_path = std::getenv("MOSLAM_BENCH_IMAGE");
  cv::Mat image = image_path != nullptr ? cv::imread(image_path) : cv::Mat();
  if (image.empty()) {
    image.create(360, 480, CV_8UC3);
    cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  }
  segmenter->Run(image);
  for (auto _ : state) {
    TorchSegmentation s = segmenter->Run(image);
    benchmark::DoNotOptimize(s.probabilities.data);
  }
  state.SetLabel(name + " " + std::to_string(state.range(1)) + "x" +
                 std::to_string(state.range(2)));
}
BENCHMARK(BM_ShippedModel)
    ->ArgNames({"model", "w", "h"})
    ->Args({0, 400, 300})  // the person card's input size
    ->Args({0, 480, 360})
    ->Args({1, 480, 360})  // the CamVid card's input size
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// The backbone alone on the same input sizes: how the time splits between backbone and head.
void BM_Backbone(benchmark::State& state) {
  BackboneOptions options;
  options.last_block = static_cast<int>(state.range(2));
  options.output_stride = static_cast<int>(state.range(3));
  torch::manual_seed(0);
  at::set_num_threads(Threads());
  MobileNetV2 backbone(options);
  backbone->eval();
  c10::InferenceMode inference;
  const torch::Tensor x = torch::rand({1, 3, state.range(1), state.range(0)}) * 2 - 1;
  backbone->forward(x);
  for (auto _ : state) benchmark::DoNotOptimize(backbone->forward(x).data_ptr());
}
BENCHMARK(BM_Backbone)
    ->ArgNames({"w", "h", "block", "os"})
    ->Args({320, 240, 13, 16})
    ->Args({480, 360, 13, 16})
    ->Args({320, 240, 17, 16})
    ->Args({480, 360, 17, 16})
    ->Args({320, 240, 13, 8})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace
}  // namespace moslam::net
