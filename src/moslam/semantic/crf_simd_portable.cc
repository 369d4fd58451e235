// The CRF's inner loops with 4-float vectors: baseline for every CPU (SSE2 on x86-64).
#include <cstdint>
#include <cstring>

#include "moslam/semantic/crf_simd.h"

namespace moslam::semantic::simd {
namespace portable {
#define MOSLAM_SIMD_WIDTH 4
#define MOSLAM_SIMD_NAME "portable (4-wide)"
#include "moslam/semantic/crf_simd_impl.inc"
}  // namespace portable

const Kernels& Portable() { return portable::kKernels; }

}  // namespace moslam::semantic::simd
