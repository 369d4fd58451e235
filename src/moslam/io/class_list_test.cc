#include "moslam/io/class_list.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::io {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

TEST(ClassList, ReadsIdsNamesMovableAndLines) {
  testing::TempDir dir;
  const std::string path = dir.Write("classes.txt", "# id name movable\n0 background 0\n7 car 1\n");
  const std::vector<ClassInfo> classes = ReadClassList(path);
  ASSERT_EQ(classes.size(), 2u);
  EXPECT_EQ(classes[1].id, 7);
  EXPECT_EQ(classes[1].name, "car");
  EXPECT_TRUE(classes[1].movable);
  EXPECT_FALSE(classes[0].movable);
  EXPECT_EQ(classes[1].line, 3);
}

TEST(ClassList, ErrorsNameFileAndLine) {
  testing::TempDir dir;
  const std::string bad_flag = dir.Write("a.txt", "0 road 0\n1 car 2\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassList(bad_flag); }), HasSubstr(bad_flag + ":2:"));
  const std::string repeated = dir.Write("b.txt", "1 car 1\n1 bus 1\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassList(repeated); }), HasSubstr("class id 1 repeated"));
  const std::string range = dir.Write("c.txt", "256 car 1\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassList(range); }), HasSubstr("0..255"));
}

}  // namespace
}  // namespace moslam::io
