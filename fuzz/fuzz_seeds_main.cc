// moslam_fuzz_seeds SOURCE_DIR OUT_DIR: writes the fuzzers' seed corpus (scripts/fuzz.sh).
#include <cstdio>

#include "fuzz_targets.h"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s SOURCE_DIR OUT_DIR\n", argv[0]);
    return 2;
  }
  const int n = moslam::fuzz::WriteSeeds(argv[1], argv[2]);
  std::printf("%d seeds written to %s\n", n, argv[2]);
  return 0;
}
