#include "moslam/util/process.h"

#include <unistd.h>

#include <cstdio>

namespace moslam {

uint64_t ResidentSetBytes() {
  // statm: size resident shared text lib data dt, in pages. One fscanf of two numbers: cheap
  // enough to call after every frame (a few microseconds).
  std::FILE* file = std::fopen("/proc/self/statm", "r");
  if (file == nullptr) return 0;
  unsigned long long size = 0, resident = 0;
  const int read = std::fscanf(file, "%llu %llu", &size, &resident);
  std::fclose(file);
  if (read != 2) return 0;
  const long page = sysconf(_SC_PAGESIZE);
  return page > 0 ? resident * static_cast<uint64_t>(page) : 0;
}

}  // namespace moslam
