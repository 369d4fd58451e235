// Bad input or configuration: the second error tier (see util/check.h).
//
// An InputError always says what was wrong and where: a file, and a line or key when one applies,
// so that a user can fix the input without reading moslam's source.
#pragma once

#include <stdexcept>
#include <string>

#include <fmt/format.h>

namespace moslam {

class InputError : public std::runtime_error {
 public:
  explicit InputError(const std::string& message) : std::runtime_error(message) {}
};

// "<path>:<line>: <message>", the format compilers use, so editors can jump to it.
[[noreturn]] void ThrowAtLine(const std::string& path, int line, const std::string& message);
// "<path>: <message>".
[[noreturn]] void ThrowInFile(const std::string& path, const std::string& message);

template <typename... Args>
[[noreturn]] void ThrowInput(fmt::format_string<Args...> format, Args&&... args) {
  throw InputError(fmt::format(format, std::forward<Args>(args)...));
}

}  // namespace moslam
