// Invariant checks: the first of moslam's three error tiers.
//
//   1. A broken invariant (a bug in moslam) aborts through MOSLAM_CHECK, with file, line and
//   message.
//   2. Bad input or configuration throws moslam::InputError (util/error.h) naming what and where.
//   3. Expected failures (tracking lost, RANSAC failed) are returned as results, never thrown.
//
// MOSLAM_CHECK is active in every build type: the checks guard cheap conditions only.
#pragma once

#include <sstream>
#include <string>

namespace moslam::internal {

// Collects the message of a failed check and aborts in its destructor.
class CheckFailure {
 public:
  CheckFailure(const char* file, int line, const char* condition);
  CheckFailure(const CheckFailure&) = delete;
  CheckFailure& operator=(const CheckFailure&) = delete;
  [[noreturn]] ~CheckFailure();
  std::ostream& stream() { return message_; }

 private:
  const char* file_;
  int line_;
  const char* condition_;
  std::ostringstream message_;
};

// Makes `cond ? (void)0 : Voidify() & stream` well-formed.
struct Voidify {
  void operator&(std::ostream&) {}
};

}  // namespace moslam::internal

#define MOSLAM_CHECK_IMPL(condition, text)      \
  (condition) ? (void)0                         \
              : ::moslam::internal::Voidify() & \
                    ::moslam::internal::CheckFailure(__FILE__, __LINE__, text).stream()

// MOSLAM_CHECK(x > 0) << "x is " << x;
#define MOSLAM_CHECK(condition) MOSLAM_CHECK_IMPL(condition, #condition)

#define MOSLAM_CHECK_OP(a, op, b) \
  MOSLAM_CHECK_IMPL((a)op(b), #a " " #op " " #b) << "(" << (a) << " vs " << (b) << ") "
#define MOSLAM_CHECK_EQ(a, b) MOSLAM_CHECK_OP(a, ==, b)
#define MOSLAM_CHECK_NE(a, b) MOSLAM_CHECK_OP(a, !=, b)
#define MOSLAM_CHECK_LT(a, b) MOSLAM_CHECK_OP(a, <, b)
#define MOSLAM_CHECK_LE(a, b) MOSLAM_CHECK_OP(a, <=, b)
#define MOSLAM_CHECK_GT(a, b) MOSLAM_CHECK_OP(a, >, b)
#define MOSLAM_CHECK_GE(a, b) MOSLAM_CHECK_OP(a, >=, b)
