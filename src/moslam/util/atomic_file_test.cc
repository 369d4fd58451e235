#include "moslam/util/atomic_file.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/file_size_limit.h"
#include "moslam/testing/shared_data.h"

namespace moslam {
namespace {

namespace fs = std::filesystem;
using ::moslam::testing::ErrorOf;
using ::testing::AllOf;
using ::testing::HasSubstr;

std::string Contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The names in `folder`: what a failed write left behind.
std::vector<std::string> Entries(const std::string& folder) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(folder)) {
    names.push_back(entry.path().filename().string());
  }
  return names;
}

TEST(AtomicFile, WritesTheWholeContentsAndReplacesAnOldFile) {
  testing::TempDir dir;
  const std::string path = dir.Write("out.txt", "old contents\n");
  WriteFileAtomically(path, "new\ncontents\n", "list");
  EXPECT_EQ(Contents(path), "new\ncontents\n");
  EXPECT_EQ(Entries(dir.path()), std::vector<std::string>{"out.txt"});
  WriteFileAtomically(path, "", "list");  // an empty file is a file
  EXPECT_TRUE(fs::exists(path));
  EXPECT_EQ(fs::file_size(path), 0u);
}

TEST(AtomicFile, AMissingFolderIsNamed) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/no/such/out.txt";
  EXPECT_THAT(ErrorOf([&] { WriteFileAtomically(path, "x", "trajectory"); }),
              AllOf(HasSubstr(path), HasSubstr("trajectory"), HasSubstr("No such file")));
}

TEST(AtomicFile, AFullDiskLeavesTheOldFileAndNoTemporary) {
  testing::TempDir dir;
  const std::string path = dir.Write("frames.csv", "the previous run's complete file\n");
  const std::string big(64 * 1024, 'x');
  std::string message;
  {
    const testing::FileSizeLimit limit(4096);
    message = ErrorOf([&] { WriteFileAtomically(path, big, "per-frame log"); });
  }
  EXPECT_THAT(message, AllOf(HasSubstr(path), HasSubstr("per-frame log"), HasSubstr("65536 bytes"),
                             HasSubstr("File too large")));
  EXPECT_EQ(Contents(path), "the previous run's complete file\n");
  EXPECT_FALSE(fs::exists(TemporaryPathFor(path)));
  EXPECT_EQ(Entries(dir.path()), std::vector<std::string>{"frames.csv"});
  // Under the limit the same call succeeds.
  WriteFileAtomically(path, big, "per-frame log");
  EXPECT_EQ(Contents(path), big);
}

}  // namespace
}  // namespace moslam
