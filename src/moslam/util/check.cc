#include "moslam/util/check.h"

#include <cstdio>
#include <cstdlib>
#include <string>

#include <fmt/format.h>

namespace moslam::internal {

CheckFailure::CheckFailure(const char* file, int line, const char* condition)
    : file_(file), line_(line), condition_(condition) {}

CheckFailure::~CheckFailure() {
  // Written straight to stderr as well as to the log: the default logger may write to stdout,
  // and the message must survive whatever state the logging setup is in.
  const std::string text =
      fmt::format("{}:{}: check failed: {} {}", file_, line_, condition_, message_.str());
  std::fputs((text + "\n").c_str(), stderr);
  std::fflush(stderr);
  std::abort();
}

}  // namespace moslam::internal
