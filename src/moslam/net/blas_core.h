// Which OpenBLAS kernels the networks' matrix products run on, and the right ones when OpenBLAS
// does not know the CPU.
//
// Debian's OpenBLAS (0.3.21, DYNAMIC_ARCH) picks its kernels once, when the library loads, from
// the CPU's model number. On a CPU newer than the build (seen: a Xeon with AVX-512 that reports a
// generic model name) it falls back to Prescott, its SSE3 kernels: the shipped network then runs
// 1.5-2x slower, silently. The choice can be forced only through OPENBLAS_CORETYPE, read at load
// time, before main; so `moslam` checks at start-up (apps/moslam/main.cc) and, when OpenBLAS fell
// back to a core without AVX2 on a CPU that has AVX2 and FMA (or AVX-512), runs itself again with
// OPENBLAS_CORETYPE set to the core that fits the CPU: SkylakeX (AVX-512) or Haswell (AVX2+FMA).
// On a CPU OpenBLAS recognises (any AVX2 or AVX-512 core chosen) nothing changes, and a
// coretype the user set is kept.
#pragma once

#include <optional>
#include <string>

namespace moslam::net {

// The instruction sets that decide which OpenBLAS kernels fit (CPUID and OS support, as the
// compiler's __builtin_cpu_supports reports them).
struct CpuFeatures {
  bool avx2 = false;
  bool fma = false;
  bool avx512 = false;  // F, CD, BW, DQ and VL: what OpenBLAS's SkylakeX kernels need
  static CpuFeatures Detect();
};

// The widest vector instructions an OpenBLAS core's kernels use: 0 SSE (Prescott, Core2,
// Nehalem, Atom, Opteron, ... and unknown names), 1 AVX (Sandybridge, Bulldozer, Piledriver,
// Steamroller), 2 AVX2 (Haswell, Zen, Excavator), 3 AVX-512 (SkylakeX, Cooperlake,
// SapphireRapids). Case-insensitive.
int OpenBlasCoreLevel(const std::string& core);

// The core to force when `current` (openblas_get_corename) is a fallback below AVX2 on a CPU that
// can do better; nullopt when `current` fits (or the CPU has no AVX2 + FMA).
std::optional<std::string> BetterOpenBlasCore(const std::string& current, const CpuFeatures& cpu);

// The name of the core OpenBLAS chose in this process, through its openblas_get_corename
// (looked up at run time, so that another BLAS behind libblas.so.3 is no error); empty when the
// process's BLAS is not OpenBLAS.
std::string OpenBlasCore();

// Set by apps/moslam/main.cc on the run where it forced the core: the core OpenBLAS had chosen
// by itself (MOSLAM_OPENBLAS_FALLBACK).
constexpr const char* kOpenBlasFallbackVariable = "MOSLAM_OPENBLAS_FALLBACK";

// For logs and summary.json: "Zen", or "SkylakeX (set by moslam; OpenBLAS chose Prescott)", or
// "none (not OpenBLAS)".
std::string DescribeOpenBlasCore();

}  // namespace moslam::net
