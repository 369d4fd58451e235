#include "moslam/util/yaml.h"
#include "moslam/testing/error_of.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

using ::moslam::testing::ErrorOf;

TEST(YamlFile, ReadsFlatOpenCvStyleAndNestedKeys) {
  testing::TempDir dir;
  const std::string path = dir.Write("s.yaml",
                                     "%YAML:1.0\n"
                                     "Camera.fx: 535.4\n"
                                     "Camera.RGB: 1\n"
                                     "name: \"kinect\"\n"
                                     "tracking:\n"
                                     "  iterations: 4\n"
                                     "  list: [1, 2.5]\n");
  YamlFile file(path);
  EXPECT_DOUBLE_EQ(file.Required<double>("Camera.fx"), 535.4);
  EXPECT_TRUE(file.Required<bool>("Camera.RGB"));
  EXPECT_EQ(file.Required<std::string>("name"), "kinect");
  EXPECT_EQ(file.Required<int>("tracking.iterations"), 4);
  EXPECT_EQ(file.Required<std::vector<double>>("tracking.list"), (std::vector<double>{1, 2.5}));
  EXPECT_NO_THROW(file.RejectUnread());
}

TEST(YamlFile, ReadsListsOfStrings) {
  testing::TempDir dir;
  YamlFile file(dir.Write("s.yaml", "%YAML:1.0\nnames: [person, \"car\"]\nnumbers: [1, 2]\n"));
  EXPECT_EQ(file.Required<std::vector<std::string>>("names"),
            (std::vector<std::string>{"person", "car"}));
  std::vector<std::string> wrong;
  EXPECT_THAT(ErrorOf([&] { file.Read("numbers", &wrong); }),
              AllOf(HasSubstr("numbers"), HasSubstr("a list of strings")));
}

TEST(YamlFile, IntegerKeyReadAsDoubleAndOptionalKeepsDefault) {
  testing::TempDir dir;
  YamlFile file(dir.Write("s.yaml", "%YAML:1.0\na: 3\n"));
  double a = 0;
  EXPECT_TRUE(file.Read("a", &a));
  EXPECT_DOUBLE_EQ(a, 3.0);
  int b = 7;
  EXPECT_FALSE(file.Read("b", &b));
  EXPECT_EQ(b, 7);
}

TEST(YamlFile, UnknownKeyIsAnErrorNamingKeyAndFile) {
  testing::TempDir dir;
  const std::string path = dir.Write("s.yaml", "%YAML:1.0\nCamera.fx: 1\nCamera.fxx: 2\n");
  YamlFile file(path);
  file.Required<double>("Camera.fx");
  EXPECT_THAT(ErrorOf([&] { file.RejectUnread(); }),
              AllOf(HasSubstr("Camera.fxx"), HasSubstr(path)));
}

TEST(YamlFile, IgnoredPrefixIsAccepted) {
  testing::TempDir dir;
  YamlFile file(dir.Write("s.yaml", "%YAML:1.0\nViewer.PointSize: 2\n"));
  file.IgnorePrefix("Viewer.");
  EXPECT_NO_THROW(file.RejectUnread());
}

TEST(YamlFile, MissingRequiredKeyAndWrongTypeNameTheKey) {
  testing::TempDir dir;
  const std::string path = dir.Write("s.yaml", "%YAML:1.0\nn: \"many\"\nf: 1.5\n");
  YamlFile file(path);
  EXPECT_THAT(ErrorOf([&] { file.Required<double>("Camera.fy"); }),
              AllOf(HasSubstr("Camera.fy"), HasSubstr("missing"), HasSubstr(path)));
  EXPECT_THAT(ErrorOf([&] { file.Required<double>("n"); }), HasSubstr("'n' must be a number"));
  EXPECT_THAT(ErrorOf([&] { file.Required<int>("f"); }), HasSubstr("'f' must be an integer"));
}

TEST(YamlFile, MissingOrMalformedFileIsAnInputError) {
  testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { YamlFile f(dir.path() + "/none.yaml"); }), HasSubstr("none.yaml"));
  const std::string bad = dir.Write("bad.yaml", "%YAML:1.0\na: [1, 2\nb: {\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(bad); }), HasSubstr("bad.yaml"));
  // Issue 31: a key without a value is named at its line (OpenCV stops at the next one), and
  // other parse errors at the line OpenCV's parser gives, with its reason.
  const std::string empty_value = dir.Write("e.yaml", "%YAML:1.0\na: 1\nb: \nc: 3\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(empty_value); }),
              HasSubstr(empty_value + ":3: key 'b' has no value"));
  const std::string last = dir.Write("last.yaml", "%YAML:1.0\na: 1\nb:\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(last); }), HasSubstr(last + ":3: key 'b' has no value"));
  const std::string indent = dir.Write("i.yaml", "%YAML:1.0\na: 1\n  b: 2\nc: 3\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(indent); }), HasSubstr(indent + ":"));
  const std::string both =
      dir.Write("m.yaml", "%YAML:1.0\nD: 0.5\n   rows: 1\n   cols: 1\n   data: [1.0]\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(both); }),
              HasSubstr(both + ":2: key 'D' has a value and a block indented below it"));
  for (const char* value : {"\"12\"", "[1, 2]", "{a: 1}"}) {
    const std::string quoted =
        dir.Write("q.yaml", fmt::format("%YAML:1.0\nD: {}\n   rows: 1\n   data: [1.0]\n", value));
    EXPECT_THAT(ErrorOf([&] { YamlFile f(quoted); }),
                HasSubstr(quoted + ":2: key 'D' has a value and a block"))
        << value;
  }
  // A key may open a block indented below it: a map or a list; a list may go on over lines.
  const std::string blocks =
      dir.Write("b.yaml", "%YAML:1.0\nm:\n  x: 1\nn:\n   - 3\nl: [1,\n     2]\n");
  YamlFile f(blocks);
  EXPECT_EQ(f.Required<int>("m.x"), 1);
  EXPECT_EQ(f.Required<std::vector<double>>("l"), (std::vector<double>{1, 2}));
  EXPECT_EQ(f.Required<std::vector<double>>("n"), (std::vector<double>{3}));
}

TEST(YamlFile, HexadecimalAndOctalNumbersAreRefusedNamingKeyAndLine) {
  testing::TempDir dir;
  const std::string hex = dir.Write("hex.yaml", "%YAML:1.0\na: 1\nCamera.fx: 0x217\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(hex); }),
              AllOf(HasSubstr(hex + ":3:"), HasSubstr("Camera.fx"), HasSubstr("0x217"),
                    HasSubstr("decimal")));
  const std::string octal = dir.Write("octal.yaml", "%YAML:1.0\nlist: [1, -017]\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(octal); }),
              AllOf(HasSubstr(octal + ":2:"), HasSubstr("list"), HasSubstr("-017")));
  // Decimal numbers, quoted text and comments may hold anything.
  const std::string fine =
      dir.Write("fine.yaml",
                "%YAML:1.0\na: 0.5\nb: 0\nc: -0.25e-3\nd: \"0x1f\"\ne: '017' # 0x2 in a comment\n");
  YamlFile f(fine);
  EXPECT_DOUBLE_EQ(f.Required<double>("a"), 0.5);
  EXPECT_EQ(f.Required<int>("b"), 0);
  EXPECT_DOUBLE_EQ(f.Required<double>("c"), -0.25e-3);
  EXPECT_EQ(f.Required<std::string>("d"), "0x1f");
  EXPECT_EQ(f.Required<std::string>("e"), "017");
}

// Issue 31: OpenCV 4.6 loops forever on a "!!binary" block whose header names no element type;
// tags are refused before OpenCV parses the file, naming the line. (Without the fix this test
// hangs rather than fails, which ctest's timeout reports.)
TEST(YamlFile, YamlTagsOtherThanOpenCvMatrixAreRefusedBeforeParsing) {
  testing::TempDir dir;
  const std::string hang = dir.Write(
      "hang.yaml", "%YAML:1.0\na: 1\nx: !!binary |\n   AAAAAAAAAAAAAAAAAAAAAAAAAAAAAAAA\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(hang); }),
              AllOf(HasSubstr(hang + ":3:"), HasSubstr("key 'x'"), HasSubstr("!!binary")));
  const std::string str = dir.Write("str.yaml", "%YAML:1.0\nlist: [1, !!str 2]\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(str); }), AllOf(HasSubstr(str + ":2:"), HasSubstr("!!str")));
  // Matrices keep their tag; a '!' inside text or a comment is no tag.
  const std::string fine = dir.Write("fine.yaml",
                                     "%YAML:1.0\nm: !!opencv-matrix\n   rows: 1\n   cols: 1\n"
                                     "   dt: d\n   data: [2.0]\nname: \"!!binary\"\n"
                                     "b: hi!\n# !!binary in a comment\n");
  YamlFile f(fine);
  EXPECT_EQ(f.Required<std::vector<double>>("m"), std::vector<double>{2.0});
  EXPECT_EQ(f.Required<std::string>("name"), "!!binary");
  EXPECT_EQ(f.Required<std::string>("b"), "hi!");
}

TEST(YamlFile, AListAtTheTopOrADirectoryIsNamed) {
  testing::TempDir dir;
  const std::string list = dir.Write("list.yaml", "%YAML:1.0\n- a\n- b\n");
  EXPECT_THAT(ErrorOf([&] { YamlFile f(list); }), AllOf(HasSubstr(list), HasSubstr("top level")));
  EXPECT_THAT(ErrorOf([&] { YamlFile f(dir.path()); }),
              AllOf(HasSubstr(dir.path()), HasSubstr("is a directory")));
}

TEST(YamlFile, AHugeKeyIsQuotedAsAnExcerpt) {
  testing::TempDir dir;
  const std::string key(1 << 20, 'k');
  const std::string path = dir.Write("huge.yaml", "%YAML:1.0\n" + key + ": 1\n");
  YamlFile f(path);
  const std::string message = ErrorOf([&] { f.RejectUnread(); });
  EXPECT_THAT(message, AllOf(HasSubstr(path), HasSubstr("unknown key"), HasSubstr("...")));
  EXPECT_LT(message.size(), 400u);
}

}  // namespace
}  // namespace moslam
