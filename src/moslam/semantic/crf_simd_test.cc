#include "moslam/semantic/crf_simd.h"

#include <cmath>
#include <cstdlib>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace moslam::semantic::simd {
namespace {

std::vector<const Kernels*> AllSets() {
  std::vector<const Kernels*> sets = {&Portable()};
  if (Avx2() != nullptr) sets.push_back(Avx2());
  return sets;
}

TEST(CrfSimd, ExpIsAccurateOverTheSoftmaxRange) {
  std::vector<float> x;
  for (float v = -87.0f; v <= 20.0f; v += 0.01f) x.push_back(v);
  for (const Kernels* k : AllSets()) {
    std::vector<float> y(x.size());
    k->exp(x.data(), y.data(), static_cast<int64_t>(x.size()));
    double worst = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      const double exact = std::exp(static_cast<double>(x[i]));
      worst = std::max(worst, std::fabs(y[i] - exact) / exact);
    }
    EXPECT_LT(worst, 4e-6) << k->name;
    // Clamped, not wrapped, outside the range.
    const float outside[2] = {-1000.0f, 1000.0f};
    float clamped[2];
    k->exp(outside, clamped, 2);
    EXPECT_GT(clamped[0], 0.0f) << k->name;
    EXPECT_LT(clamped[0], 1e-37f) << k->name;
    EXPECT_GT(clamped[1], 1e38f) << k->name;
  }
}

TEST(CrfSimd, LogIsAccurateForClampedProbabilities) {
  std::vector<float> x;
  for (float v = 1e-8f; v <= 1.0f; v *= 1.001f) x.push_back(v);
  x.push_back(1.0f);
  for (const Kernels* k : AllSets()) {
    std::vector<float> y(x.size());
    k->log(x.data(), y.data(), static_cast<int64_t>(x.size()));
    double worst = 0.0;
    for (size_t i = 0; i < x.size(); ++i) {
      worst = std::max(worst, std::fabs(y[i] - std::log(static_cast<double>(x[i]))));
    }
    EXPECT_LT(worst, 2e-6) << k->name;
  }
}

TEST(CrfSimd, ActiveSetFollowsTheEnvironment) {
  const char* choice = std::getenv("MOSLAM_SIMD");
  if (choice != nullptr && std::string(choice) == "portable") {
    EXPECT_EQ(&Active(), &Portable());
  } else if (Avx2() != nullptr) {
    EXPECT_EQ(&Active(), Avx2());
  } else {
    EXPECT_EQ(&Active(), &Portable());
  }
  EXPECT_TRUE(Active().tile == 4 || Active().tile == 8);
}

}  // namespace
}  // namespace moslam::semantic::simd
