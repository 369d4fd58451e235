#include "moslam/util/check.h"

#include <gtest/gtest.h>

namespace moslam {
namespace {

TEST(CheckDeathTest, FailedCheckAbortsWithConditionAndMessage) {
  const int x = 3;
  EXPECT_DEATH(MOSLAM_CHECK(x > 5) << "x was " << x, "check failed: x > 5 x was 3");
  EXPECT_DEATH(MOSLAM_CHECK_EQ(x, 4), "x == 4");
}

TEST(Check, PassingCheckDoesNothing) {
  int evaluated = 0;
  MOSLAM_CHECK(++evaluated == 1) << "never printed";
  EXPECT_EQ(evaluated, 1);  // the condition is evaluated exactly once
}

}  // namespace
}  // namespace moslam
