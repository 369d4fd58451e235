#include "moslam/testing/shared_data.h"

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>

namespace moslam::testing {

std::string SharedRoot() {
  if (const char* env = std::getenv("MOSLAM_SHARED"); env != nullptr && *env != '\0') return env;
  return std::string(MOSLAM_SOURCE_DIR) + "/../shared";
}

std::string FindShared(const std::string& relative) {
  const std::string path = SharedRoot() + "/" + relative;
  std::error_code ec;
  return std::filesystem::exists(path, ec) ? path : std::string();
}

TempDir::TempDir() {
  std::random_device rd;
  const auto base = std::filesystem::temp_directory_path();
  for (int attempt = 0; attempt < 100; ++attempt) {
    const auto candidate = base / ("moslam_test_" + std::to_string(rd()));
    if (std::filesystem::create_directory(candidate)) {
      path_ = candidate.string();
      return;
    }
  }
  ADD_FAILURE() << "could not create a temporary directory under " << base;
}

TempDir::~TempDir() {
  std::error_code ec;
  if (!path_.empty()) std::filesystem::remove_all(path_, ec);
}

std::string TempDir::Write(const std::string& name, const std::string& contents) const {
  const std::filesystem::path full = std::filesystem::path(path_) / name;
  std::filesystem::create_directories(full.parent_path());
  std::ofstream out(full, std::ios::binary);
  out << contents;
  return full.string();
}

}  // namespace moslam::testing
