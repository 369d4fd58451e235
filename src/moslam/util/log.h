// Logging goes through spdlog; library code never writes to std::cout.
#pragma once

#include <string>

namespace moslam {

// Sets the global spdlog level from a name: trace, debug, info, warn, error, critical, off.
// Throws InputError for an unknown name. Log lines go to stderr so that stdout carries results.
void SetupLogging(const std::string& level);

}  // namespace moslam
