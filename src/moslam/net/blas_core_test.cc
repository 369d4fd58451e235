// The OpenBLAS core choice (net/blas_core.h): which fallbacks are replaced and by what, and that a
// forced core computes the shipped network's output as the core OpenBLAS chose does. The second
// needs two processes (OpenBLAS reads OPENBLAS_CORETYPE once, when it loads): the test runs its own
// binary again with the generic Prescott kernels forced and compares the outputs.
#include "moslam/net/blas_core.h"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/net/torch_segmenter.h"
#include "moslam/testing/shared_data.h"

extern char** environ;

namespace moslam::net {
namespace {

CpuFeatures Cpu(bool avx2, bool avx512) {
  CpuFeatures f;
  f.avx2 = f.fma = avx2;
  f.avx512 = avx512;
  return f;
}

TEST(BlasCore, GenericFallbacksAreReplacedByTheCoreTheCpuCanRun) {
  // The case seen on an AVX-512 Xeon OpenBLAS 0.3.21 does not know: Prescott (SSE3).
  EXPECT_EQ(BetterOpenBlasCore("Prescott", Cpu(true, true)), "SkylakeX");
  EXPECT_EQ(BetterOpenBlasCore("Prescott", Cpu(true, false)), "Haswell");
  EXPECT_EQ(BetterOpenBlasCore("NEHALEM", Cpu(true, false)), "Haswell");
  EXPECT_EQ(BetterOpenBlasCore("Sandybridge", Cpu(true, true)), "SkylakeX");
  EXPECT_EQ(BetterOpenBlasCore("Unknown", Cpu(true, false)), "Haswell");
  // OpenBLAS's own informed choices stay, and a CPU without AVX2 keeps whatever it got.
  EXPECT_EQ(BetterOpenBlasCore("Zen", Cpu(true, false)), std::nullopt);
  EXPECT_EQ(BetterOpenBlasCore("Zen", Cpu(true, true)), std::nullopt);
  EXPECT_EQ(BetterOpenBlasCore("Haswell", Cpu(true, true)), std::nullopt);
  EXPECT_EQ(BetterOpenBlasCore("SkylakeX", Cpu(true, true)), std::nullopt);
  EXPECT_EQ(BetterOpenBlasCore("Prescott", Cpu(false, false)), std::nullopt);
  EXPECT_EQ(OpenBlasCoreLevel("cooperlake"), 3);
  EXPECT_EQ(OpenBlasCoreLevel("Excavator"), 2);
  EXPECT_EQ(OpenBlasCoreLevel("Piledriver"), 1);
  EXPECT_EQ(OpenBlasCoreLevel("Core2"), 0);
}

// The shipped person network's probabilities on a fixed image (a synthetic gradient with
// shapes), written one float a line.
std::vector<float> ShippedNetworkOutput() {
  TorchSegmenter segmenter("data/models/weak_synth_person.mnet", 1);
  cv::Mat image(240, 320, CV_8UC3);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      image.at<cv::Vec3b>(y, x) =
          cv::Vec3b(static_cast<uint8_t>(x * 255 / 320), static_cast<uint8_t>(y * 255 / 240),
                    static_cast<uint8_t>((x + y) % 256));
    }
  }
  cv::rectangle(image, {100, 60}, {160, 220}, cv::Scalar(30, 60, 200), cv::FILLED);
  cv::circle(image, {130, 45}, 18, cv::Scalar(120, 150, 220), cv::FILLED);
  const TorchSegmentation out = segmenter.Run(image);
  const cv::Mat flat = out.probabilities.reshape(1, 1);
  return std::vector<float>(flat.begin<float>(), flat.end<float>());
}

constexpr const char* kChildOut = "MOSLAM_BLAS_CORE_TEST_OUT";

// Run by ForcedGenericCoreComputesTheSameNetworkOutput in a second process; skipped otherwise.
TEST(BlasCore, ChildWritesTheNetworkOutput) {
  const char* path = std::getenv(kChildOut);
  if (path == nullptr) GTEST_SKIP() << "the second process of ForcedGenericCore... only";
  std::ofstream out(path);
  out.precision(9);
  out << OpenBlasCore() << "\n";
  for (float v : ShippedNetworkOutput()) out << v << "\n";
}

TEST(BlasCore, ForcedGenericCoreComputesTheSameNetworkOutput) {
  const std::string core = OpenBlasCore();
  if (core.empty()) GTEST_SKIP() << "libblas.so.3 is not OpenBLAS here";
  std::printf("OpenBLAS core in this process: %s (%s)\n", core.c_str(),
              DescribeOpenBlasCore().c_str());
  testing::TempDir dir;
  const std::string path = dir.path() + "/child.txt";
  // The same binary, the child test only, with the generic kernels forced.
  std::vector<std::string> env_strings = {"OPENBLAS_CORETYPE=Prescott",
                                          std::string(kChildOut) + "=" + path};
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string s = *e;
    if (s.rfind("OPENBLAS_CORETYPE=", 0) != 0 && s.rfind(kChildOut, 0) != 0) {
      env_strings.push_back(s);
    }
  }
  std::vector<char*> envp;
  for (auto& s : env_strings) envp.push_back(s.data());
  envp.push_back(nullptr);
  std::string exe = "/proc/self/exe",
              filter = "--gtest_filter=BlasCore.ChildWritesTheNetworkOutput";
  char* argv[] = {exe.data(), filter.data(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv, envp.data()), 0);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "child failed";

  std::ifstream in(path);
  std::string child_core;
  std::getline(in, child_core);
  EXPECT_EQ(child_core, "Prescott") << "OPENBLAS_CORETYPE was not honoured";
  std::vector<float> child;
  for (float v; in >> v;) child.push_back(v);
  const std::vector<float> here = ShippedNetworkOutput();
  ASSERT_EQ(child.size(), here.size());
  ASSERT_GT(here.size(), 1000u);
  double max_diff = 0.0;
  for (size_t i = 0; i < here.size(); ++i) {
    max_diff = std::max(max_diff, static_cast<double>(std::abs(here[i] - child[i])));
  }
  std::printf("%zu probabilities, largest difference %s vs Prescott: %.3g\n", here.size(),
              core.c_str(), max_diff);
  // Different kernels sum in a different order: float rounding, nothing more (the printed text
  // itself keeps 6 significant digits).
  EXPECT_LT(max_diff, 1e-4);
}

}  // namespace
}  // namespace moslam::net
