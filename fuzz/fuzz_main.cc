// libFuzzer entry of one harness (fuzz_targets.h); MOSLAM_FUZZ_TARGET names it at compile time.
#include <spdlog/spdlog.h>

#include "fuzz_targets.h"

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  spdlog::set_level(spdlog::level::off);  // parsers warn on odd but accepted input
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const moslam::fuzz::FuzzTarget& target = moslam::fuzz::FindTarget(MOSLAM_FUZZ_TARGET);
  moslam::fuzz::RunOne(target, data, size);
  return 0;
}
