// The CRF's inner loops with 8-float vectors and FMA. This file alone is compiled with
// -mavx2 -mfma (see CMakeLists.txt); Avx2Kernels() is only called after a CPU check.
#include <cstdint>
#include <cstring>

#include "moslam/semantic/crf_simd.h"

namespace moslam::semantic::simd {
namespace avx2 {
#define MOSLAM_SIMD_WIDTH 8
#define MOSLAM_SIMD_NAME "avx2 (8-wide, FMA)"
#include "moslam/semantic/crf_simd_impl.inc"
}  // namespace avx2

const Kernels& Avx2Kernels() { return avx2::kKernels; }

}  // namespace moslam::semantic::simd
