// Whole-system tests that take minutes under AddressSanitizer skip themselves there.
//
// CI runs the suite twice, in a Release build and under ASan+UBSan (.ci/run), on 2 cores within
// 90 minutes. Under ASan a few end-to-end runs cost 3-7x their release time (measured on one
// 2-core machine: LoopRoom monocular 570 s, KITTI 07 monocular 340 s, the aliasing street 266 s,
// the KITTI kidnap 150 s, against 87 / 43 / 39 / 40 s in Release), half of the sanitized suite.
// They still run in the Release suite, and the code they drive runs under ASan in the shorter
// end-to-end tests (loop_room RGB-D, the synthetic relocalization gaps, the other KITTI tests)
// and in the unit tests. MOSLAM_SANITIZED is defined by the top CMakeLists.txt when
// MOSLAM_SANITIZE is set.
#pragma once

#include <gtest/gtest.h>

#if defined(MOSLAM_SANITIZED)
#define MOSLAM_SKIP_UNDER_SANITIZER(why) \
  GTEST_SKIP() << "skipped in a sanitizer build (testing/sanitizer.h): " << (why)
#else
#define MOSLAM_SKIP_UNDER_SANITIZER(why) static_cast<void>(0)
#endif
