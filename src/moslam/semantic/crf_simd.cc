#include "moslam/semantic/crf_simd.h"

#include <cstdlib>
#include <cstring>

namespace moslam::semantic::simd {

#if defined(MOSLAM_HAVE_AVX2_KERNELS)
const Kernels& Avx2Kernels();  // crf_simd_avx2.cc
#endif

const Kernels* Avx2() {
#if defined(MOSLAM_HAVE_AVX2_KERNELS)
  static const bool supported = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return supported ? &Avx2Kernels() : nullptr;
#else
  return nullptr;
#endif
}

const Kernels& Active() {
  static const Kernels* active = [] {
    const char* choice = std::getenv("MOSLAM_SIMD");
    const bool portable = choice != nullptr && std::strcmp(choice, "portable") == 0;
    return (!portable && Avx2() != nullptr) ? Avx2() : &Portable();
  }();
  return *active;
}

}  // namespace moslam::semantic::simd
