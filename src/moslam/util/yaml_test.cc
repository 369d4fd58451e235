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
}

}  // namespace
}  // namespace moslam
