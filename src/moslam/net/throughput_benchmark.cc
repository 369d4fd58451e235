// How close the shipped networks come to what the CPU can do: the machine's peak single-precision
// GFLOP/s, measured in the same run with a plain loop of independent FMAs (AVX-512, AVX2+FMA or
// SSE, whichever the CPU has), beside the GFLOP/s each kind of layer reaches in the networks
// (op_counter.h: multiply-adds read from libtorch's dispatch, time per operator).
//
//   ./build/src/moslam/net/bench_net_throughput                       (from the repository root)
//   MOSLAM_BENCH_THREADS=1 ./build/src/moslam/net/bench_net_throughput
//
// Counters: BM_PeakFma's GFLOPs is the peak on `threads` cores. BM_ShippedModelOps reports the
// network's multiply-adds per frame (Mmac), its GFLOP/s over the whole forward pass (GFLOPs, the
// copies and activations between layers included), and per kind of layer its share of the time
// (`<kind>_ms`) and GFLOP/s (`<kind>_GFLOPs`) and that over the peak on as many threads
// (`<kind>_of_peak`).
#include <immintrin.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <exception>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <ATen/Parallel.h>
#include <benchmark/benchmark.h>
#include <opencv2/core.hpp>

#include "moslam/net/op_counter.h"
#include "moslam/net/torch_segmenter.h"

namespace moslam::net {
namespace {

int Threads() {
  const char* value = std::getenv("MOSLAM_BENCH_THREADS");
  return value != nullptr ? std::max(1, std::atoi(value)) : 2;
}

// Each loop keeps 12 independent accumulators: enough to cover an FMA latency of 4-6 cycles on
// two FMA ports, so that the loop is bound by throughput, as a GEMM micro-kernel is. x * a + b
// with a just below 1 stays finite and normal for any number of iterations. Returns FLOPs done.
constexpr int kAccumulators = 12;

__attribute__((target("avx512f"))) double FmaLoopAvx512(int64_t iterations, float* sink) {
  __m512 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm512_set1_ps(static_cast<float>(i));
  const __m512 a = _mm512_set1_ps(0.999999f), b = _mm512_set1_ps(1e-6f);
  for (int64_t n = 0; n < iterations; ++n) {
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm512_fmadd_ps(acc[i], a, b);
  }
  for (int i = 1; i < kAccumulators; ++i) acc[0] = _mm512_add_ps(acc[0], acc[i]);
  alignas(64) float lanes[16];  // not _mm512_reduce_add_ps: GCC 12 warns inside it
  _mm512_store_ps(lanes, acc[0]);
  *sink = lanes[0];
  return 2.0 * 16 * kAccumulators * static_cast<double>(iterations);
}

__attribute__((target("avx2,fma"))) double FmaLoopAvx2(int64_t iterations, float* sink) {
  __m256 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm256_set1_ps(static_cast<float>(i));
  const __m256 a = _mm256_set1_ps(0.999999f), b = _mm256_set1_ps(1e-6f);
  for (int64_t n = 0; n < iterations; ++n) {
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm256_fmadd_ps(acc[i], a, b);
  }
  for (int i = 1; i < kAccumulators; ++i) acc[0] = _mm256_add_ps(acc[0], acc[i]);
  alignas(32) float lanes[8];
  _mm256_store_ps(lanes, acc[0]);
  *sink = lanes[0];
  return 2.0 * 8 * kAccumulators * static_cast<double>(iterations);
}

// Without FMA: a multiply and an add per lane, on separate ports.
double FmaLoopSse(int64_t iterations, float* sink) {
  __m128 acc[kAccumulators];
  for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm_set1_ps(static_cast<float>(i));
  const __m128 a = _mm_set1_ps(0.999999f), b = _mm_set1_ps(1e-6f);
  for (int64_t n = 0; n < iterations; ++n) {
    for (int i = 0; i < kAccumulators; ++i) acc[i] = _mm_add_ps(_mm_mul_ps(acc[i], a), b);
  }
  for (int i = 1; i < kAccumulators; ++i) acc[0] = _mm_add_ps(acc[0], acc[i]);
  *sink = _mm_cvtss_f32(acc[0]);
  return 2.0 * 4 * kAccumulators * static_cast<double>(iterations);
}

const char* IsaName() {
  if (__builtin_cpu_supports("avx512f")) return "avx512f";
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return "avx2+fma";
  return "sse";
}

double FmaLoop(int64_t iterations, float* sink) {
  if (__builtin_cpu_supports("avx512f")) return FmaLoopAvx512(iterations, sink);
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) {
    return FmaLoopAvx2(iterations, sink);
  }
  return FmaLoopSse(iterations, sink);
}

// The FMA loop on `threads` threads at once for about `seconds`: GFLOP/s of all of them.
double PeakGflops(int threads, double seconds) {
  constexpr int64_t kChunk = 1 << 20;
  std::vector<double> flops(threads, 0.0);
  std::vector<float> sinks(threads, 0.0f);
  const auto start = std::chrono::steady_clock::now();
  const auto until = start + std::chrono::duration<double>(seconds);
  std::vector<std::thread> workers;
  for (int t = 0; t < threads; ++t) {
    workers.emplace_back([&, t] {
      while (std::chrono::steady_clock::now() < until) flops[t] += FmaLoop(kChunk, &sinks[t]);
    });
  }
  for (std::thread& worker : workers) worker.join();
  const double elapsed =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  benchmark::DoNotOptimize(sinks.data());
  double total = 0.0;
  for (double f : flops) total += f;
  return total / elapsed * 1e-9;
}

// The peak on `threads` cores, measured once per process (0.5 s) and kept for the ratios below.
double CachedPeak(int threads) {
  static std::vector<double> peaks(64, 0.0);
  const int t = std::min(threads, 63);
  if (peaks[t] == 0.0) peaks[t] = PeakGflops(t, 0.5);
  return peaks[t];
}

void BM_PeakFma(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  double gflops = 0.0;
  for (auto _ : state) gflops = PeakGflops(threads, 0.25);
  state.counters["GFLOPs"] = gflops;
  state.SetLabel(std::string(IsaName()) + ", " + std::to_string(threads) + " thread(s)");
}
BENCHMARK(BM_PeakFma)->ArgName("threads")->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

// A shipped network (data/models, or MOSLAM_BENCH_MODELS) at its card's input size on a noise
// image, with every convolution and GEMM counted. Args: model (0 person, 1 CamVid), w, h.
void BM_ShippedModelOps(benchmark::State& state) {
  const char* folder = std::getenv("MOSLAM_BENCH_MODELS");
  const std::string name = state.range(0) == 0 ? "weak_synth_person.mnet" : "weak_camvid.mnet";
  const std::string path = std::string(folder != nullptr ? folder : "data/models") + "/" + name;
  const int threads = Threads();
  std::unique_ptr<TorchSegmenter> segmenter;
  try {
    segmenter = std::make_unique<TorchSegmenter>(path, threads);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  segmenter->set_input_size({static_cast<int>(state.range(1)), static_cast<int>(state.range(2))});
  cv::Mat image(360, 480, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  const double peak = CachedPeak(threads);
  segmenter->Run(image);  // warm-up: first call allocates
  OpCounter counter;
  double total_ms = 0.0;
  for (auto _ : state) {
    const auto start = std::chrono::steady_clock::now();
    TorchSegmentation s = segmenter->Run(image);
    total_ms +=
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    benchmark::DoNotOptimize(s.probabilities.data);
  }
  const double frames = static_cast<double>(state.iterations());
  const OpStats total = counter.count().Total();
  state.counters["Mmac"] = total.macs / frames * 1e-6;
  state.counters["GFLOPs"] = 2.0 * total.macs / (total_ms * 1e6);
  state.counters["of_peak"] = state.counters["GFLOPs"] / peak;
  state.counters["peak_GFLOPs"] = peak;
  state.counters["layers_ms"] = total.ms / frames;
  for (const auto& [kind, stats] : counter.count().by_kind) {
    const std::string k = ToString(kind);
    state.counters[k + "_Mmac"] = stats.macs / frames * 1e-6;
    state.counters[k + "_ms"] = stats.ms / frames;
    state.counters[k + "_GFLOPs"] = stats.Gflops();
    state.counters[k + "_of_peak"] = stats.Gflops() / peak;
  }
  state.SetLabel(name + " " + std::to_string(state.range(1)) + "x" +
                 std::to_string(state.range(2)) + ", " + std::to_string(threads) + " thread(s)");
}
BENCHMARK(BM_ShippedModelOps)
    ->ArgNames({"model", "w", "h"})
    ->Args({0, 400, 300})  // the person card's input size
    ->Args({1, 480, 360})  // the CamVid card's input size
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

}  // namespace
}  // namespace moslam::net
