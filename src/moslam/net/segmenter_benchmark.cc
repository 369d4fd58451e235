// TorchSegmenter::Run on a 480x360 image (CamVid's size) with 2 intra-op threads, for the default
// NetConfig and larger inputs / deeper backbones. Weights are random (ImageNet-initialized nets
// cost the same); 11 classes as CamVid. Args: input width, input height, last_block, stride.
//
//   MOSLAM_SHARED=/work/shared ./build/src/moslam/net/bench_net_segmenter
#include <string>
#include <vector>

#include <ATen/Parallel.h>
#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "moslam/net/torch_segmenter.h"

namespace moslam::net {
namespace {

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
  torch::manual_seed(0);
  at::set_num_threads(2);
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
                 std::to_string(config.backbone.output_stride));
}
BENCHMARK(BM_TorchSegmenterRun)
    ->ArgNames({"w", "h", "block", "os"})
    ->Args({320, 240, 13, 16})  // the default NetConfig
    ->Args({480, 360, 13, 16})
    ->Args({320, 240, 17, 16})
    ->Args({480, 360, 17, 16})
    ->Args({320, 240, 13, 8})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace
}  // namespace moslam::net
