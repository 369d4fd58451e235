#include "moslam/util/log.h"

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "moslam/util/error.h"

namespace moslam {

void SetupLogging(const std::string& level) {
  const spdlog::level::level_enum parsed = spdlog::level::from_str(level);
  if (parsed == spdlog::level::off && level != "off") {
    ThrowInput("unknown log level '{}' (trace, debug, info, warn, error, critical, off)", level);
  }
  auto logger = spdlog::stderr_color_mt("moslam");
  logger->set_pattern("[%H:%M:%S.%e] [%^%l%$] %v");
  spdlog::set_default_logger(logger);
  spdlog::set_level(parsed);
}

}  // namespace moslam
