#include "moslam/util/text_file.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam {
namespace {

using ::testing::HasSubstr;

TEST(TextFile, SkipsBlankAndCommentLinesAndKeepsNumbers) {
  testing::TempDir dir;
  const std::string path = dir.Write("a.txt", "# header\n\n1 2\r\n  # indented comment\n3 4\n");
  const auto lines = ReadDataLines(path);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(lines[0].number, 3);
  EXPECT_EQ(lines[0].text, "1 2");
  EXPECT_EQ(lines[1].number, 5);
}

TEST(TextFile, MissingFileNamesThePath) {
  try {
    ReadDataLines("/nonexistent/file.txt");
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr("/nonexistent/file.txt"));
  }
}

TEST(TextFile, RequireDirectoryRejectsFiles) {
  testing::TempDir dir;
  const std::string path = dir.Write("f", "x");
  EXPECT_THROW(RequireDirectory(path, "folder"), InputError);
  EXPECT_NO_THROW(RequireDirectory(dir.path(), "folder"));
}

}  // namespace
}  // namespace moslam
