#include "moslam/util/process.h"

#include <cstring>
#include <memory>

#include <gtest/gtest.h>

namespace moslam {
namespace {

TEST(Process, ResidentSetGrowsWithTouchedMemory) {
  const uint64_t before = ResidentSetBytes();
  ASSERT_GT(before, 0u) << "/proc/self/statm unreadable";
  // 64 MB written page by page becomes resident; freed memory may stay mapped, so only the
  // growth while it is held is checked.
  constexpr size_t kBytes = 64u << 20;
  auto block = std::make_unique<char[]>(kBytes);
  std::memset(block.get(), 1, kBytes);
  const uint64_t during = ResidentSetBytes();
  EXPECT_GT(during, before + kBytes / 2);
  EXPECT_EQ(block[kBytes - 1], 1);
}

}  // namespace
}  // namespace moslam
