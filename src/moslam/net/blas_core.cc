#include "moslam/net/blas_core.h"

#include <dlfcn.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>

#include <fmt/format.h>

namespace moslam::net {

CpuFeatures CpuFeatures::Detect() {
  CpuFeatures f;
#if defined(__x86_64__) || defined(__i386__)
  __builtin_cpu_init();
  f.avx2 = __builtin_cpu_supports("avx2");
  f.fma = __builtin_cpu_supports("fma");
  f.avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512cd") &&
             __builtin_cpu_supports("avx512bw") && __builtin_cpu_supports("avx512dq") &&
             __builtin_cpu_supports("avx512vl");
#endif
  return f;
}

int OpenBlasCoreLevel(const std::string& core) {
  std::string c = core;
  std::transform(c.begin(), c.end(), c.begin(), [](unsigned char x) { return std::tolower(x); });
  for (const char* name : {"skylakex", "cooperlake", "sapphirerapids"}) {
    if (c == name) return 3;
  }
  for (const char* name : {"haswell", "zen", "excavator"}) {
    if (c == name) return 2;
  }
  for (const char* name : {"sandybridge", "bulldozer", "piledriver", "steamroller"}) {
    if (c == name) return 1;
  }
  return 0;  // Prescott, Core2, Penryn, Nehalem, Atom, Opteron, Barcelona, Nano, unknown ...
}

std::optional<std::string> BetterOpenBlasCore(const std::string& current, const CpuFeatures& cpu) {
  if (!(cpu.avx2 && cpu.fma)) return std::nullopt;
  // A core with AVX2 or AVX-512 kernels is OpenBLAS's own informed choice (it picks Haswell on
  // an AVX-512 CPU whose OS does not save the AVX-512 registers, Zen on AMD): keep it.
  if (OpenBlasCoreLevel(current) >= 2) return std::nullopt;
  return std::string(cpu.avx512 ? "SkylakeX" : "Haswell");
}

std::string OpenBlasCore() {
  using CoreName = char* (*)();
  auto get = reinterpret_cast<CoreName>(dlsym(RTLD_DEFAULT, "openblas_get_corename"));
  if (get == nullptr) return "";
  const char* name = get();
  return name ? std::string(name) : std::string();
}

std::string DescribeOpenBlasCore() {
  const std::string core = OpenBlasCore();
  if (core.empty()) return "none (not OpenBLAS)";
  const char* fallback = std::getenv(kOpenBlasFallbackVariable);
  if (fallback == nullptr || *fallback == '\0') return core;
  return fmt::format("{} (set by moslam; OpenBLAS chose {})", core, fallback);
}

}  // namespace moslam::net
