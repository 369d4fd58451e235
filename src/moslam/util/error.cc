#include "moslam/util/error.h"

namespace moslam {

void ThrowAtLine(const std::string& path, int line, const std::string& message) {
  throw InputError(fmt::format("{}:{}: {}", path, line, message));
}

void ThrowInFile(const std::string& path, const std::string& message) {
  throw InputError(fmt::format("{}: {}", path, message));
}

}  // namespace moslam
