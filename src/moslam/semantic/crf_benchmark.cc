// Speed of the fully connected CRF at the reference setting of ../shared/reference/ANCHORS.md:
// 5 mean-field iterations, smoothness (sxy 3, w 3) + appearance (sxy 80, srgb 13, w 10), unaries
// from probabilities, on a 640x480 (and a 480x360) image with 2 and 21 labels, on 1 and 2
// threads. The image is a CamVid frame when ../shared is present (lattice sizes depend on the
// content), else a synthetic one. Time per call covers everything: -log p, both lattices, the
// normalization and the iterations. The inner loops use AVX2 where the CPU has it; set
// MOSLAM_SIMD=portable to time the 4-wide fallback.
//
//   build/src/moslam/semantic/bench_semantic --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true
#include <random>
#include <string>

#include <benchmark/benchmark.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/crf_simd.h"
#include "moslam/semantic/dense_crf.h"
#include "moslam/testing/shared_data.h"

namespace moslam::semantic {
namespace {

cv::Mat BenchmarkImage(cv::Size size) {
  const std::string path = testing::FindShared("data/camvid/val/0016E5_07959.jpg");
  cv::Mat image;
  if (!path.empty()) image = cv::imread(path, cv::IMREAD_COLOR);
  if (image.empty()) {
    // Synthetic stand-in: smooth gradients, a few shapes and mild noise.
    image.create(size, CV_8UC3);
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        image.at<cv::Vec3b>(y, x) = cv::Vec3b(x * 255 / size.width, y * 255 / size.height, 128);
      }
    }
    cv::circle(image, {size.width / 3, size.height / 2}, size.height / 4, {20, 200, 40}, -1);
    cv::rectangle(image, cv::Rect(size.width / 2, size.height / 4, size.width / 4, size.height / 3),
                  {220, 30, 30}, -1);
    cv::Mat noise(size, CV_8UC3);
    cv::randu(noise, 0, 12);
    image += noise;
  }
  cv::resize(image, image, size, 0, 0, cv::INTER_LINEAR);
  return image;
}

// Smooth random probabilities: blurred noise per label, normalized per pixel, planar {L, H, W}.
cv::Mat BenchmarkProbabilities(cv::Size size, int labels) {
  const int sizes[3] = {labels, size.height, size.width};
  cv::Mat probs(3, sizes, CV_32F);
  cv::Mat sum = cv::Mat::zeros(size, CV_32F);
  cv::RNG rng(42);
  for (int l = 0; l < labels; ++l) {
    cv::Mat plane = LabelPlane(probs, l);
    cv::Mat small(size.height / 16 + 1, size.width / 16 + 1, CV_32F);
    rng.fill(small, cv::RNG::UNIFORM, 0.0, 1.0);
    cv::Mat big;
    cv::resize(small, big, size, 0, 0, cv::INTER_CUBIC);
    cv::exp(big * 4.0, big);
    big.copyTo(plane);
    sum += big;
  }
  for (int l = 0; l < labels; ++l) {
    cv::Mat plane = LabelPlane(probs, l);
    cv::divide(plane, sum, plane);
  }
  return probs;
}

void BM_DenseCrf(benchmark::State& state) {
  const cv::Size size(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const int labels = static_cast<int>(state.range(2));
  DenseCrfOptions options;  // the defaults are the reference setting
  options.num_threads = static_cast<int>(state.range(3));
  // 1: the smoothness kernel on a lattice, as in the reference, instead of the automatic choice
  // (an exact separable blur for up to 5 labels).
  if (state.range(4) != 0) options.smoothness_filter = "lattice";
  const cv::Mat image = BenchmarkImage(size);
  const Unaries unaries = Unaries::FromProbabilities(BenchmarkProbabilities(size, labels));
  // One DenseCrf and one result for the whole run, as for a video stream: threads and buffers
  // are reused between frames.
  DenseCrf crf(options);
  CrfResult result;
  for (auto _ : state) {
    crf.Infer(image, cv::Mat(), unaries, &result);
    benchmark::DoNotOptimize(result.labels.data);
  }
  state.SetLabel(std::to_string(size.width) + "x" + std::to_string(size.height) + " L=" +
                 std::to_string(labels) + " threads=" + std::to_string(options.num_threads) +
                 " smoothness=" + options.smoothness_filter + " " + simd::Active().name);
}

BENCHMARK(BM_DenseCrf)
    ->ArgNames({"w", "h", "labels", "threads", "lattice"})
    ->Args({640, 480, 2, 1, 0})
    ->Args({640, 480, 2, 2, 0})
    ->Args({640, 480, 2, 1, 1})
    ->Args({640, 480, 2, 2, 1})
    ->Args({640, 480, 21, 1, 0})
    ->Args({640, 480, 21, 2, 0})
    ->Args({480, 360, 2, 1, 0})
    ->Args({480, 360, 21, 1, 0})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(1.0)
    ->UseRealTime();

}  // namespace
}  // namespace moslam::semantic
