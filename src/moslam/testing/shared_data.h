// Test support: locating ../shared and writing scratch files.
//
// Tests that need the shared data set read MOSLAM_SHARED (default: ../shared beside the source
// tree) and skip with a clear message when the data is absent:
//
//   MOSLAM_SHARED_OR_SKIP(dir, "data/trajectories");
#pragma once

#include <string>

#include <gtest/gtest.h>

namespace moslam::testing {

// MOSLAM_SHARED if set, else <source dir>/../shared.
std::string SharedRoot();
// SharedRoot()/relative if it exists, else an empty string.
std::string FindShared(const std::string& relative);

// A fresh directory under the system temp dir, removed when the object dies.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::string& path() const { return path_; }
  // Writes `contents` to path()/name and returns the full path.
  std::string Write(const std::string& name, const std::string& contents) const;

 private:
  std::string path_;
};

}  // namespace moslam::testing

// Declares `const std::string var` = the shared path, or skips the test when it is absent.
#define MOSLAM_SHARED_OR_SKIP(var, relative)                                          \
  const std::string var = ::moslam::testing::FindShared(relative);                    \
  if (var.empty())                                                                    \
  GTEST_SKIP() << "shared data not found: " << ::moslam::testing::SharedRoot() << "/" \
               << (relative) << " (set MOSLAM_SHARED to the folder that holds data/)"
