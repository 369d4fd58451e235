#include "moslam/util/strings.h"

#include <cmath>

#include <gtest/gtest.h>

namespace moslam {
namespace {

TEST(Strings, TrimRemovesSurroundingWhitespace) {
  EXPECT_EQ(Trim("  a b\t\r\n"), "a b");
  EXPECT_EQ(Trim(" \t "), "");
}

TEST(Strings, SplitFieldsDropsEmptyFields) {
  const auto f = SplitFields("1  2\t3 ");
  ASSERT_EQ(f.size(), 3u);
  EXPECT_EQ(f[2], "3");
  EXPECT_EQ(SplitFields("a,b, c", true).size(), 3u);
  EXPECT_EQ(SplitFields("a,b", false).size(), 1u);
}

TEST(Strings, ParseDoubleIsStrict) {
  EXPECT_DOUBLE_EQ(*ParseDouble("1.5e3"), 1500.0);
  EXPECT_DOUBLE_EQ(*ParseDouble(" -2 "), -2.0);
  EXPECT_FALSE(ParseDouble("1.5abc"));
  EXPECT_FALSE(ParseDouble(""));
  EXPECT_FALSE(ParseDouble("1e999"));
  EXPECT_TRUE(std::isnan(*ParseDouble("nan")));
}

TEST(Strings, ParseIntIsStrict) {
  EXPECT_EQ(*ParseInt("42"), 42);
  EXPECT_FALSE(ParseInt("4.2"));
  EXPECT_FALSE(ParseInt("x"));
}

TEST(Strings, Affixes) {
  EXPECT_TRUE(StartsWith("Camera.fx", "Camera."));
  EXPECT_FALSE(StartsWith("Cam", "Camera."));
  EXPECT_TRUE(EndsWith("a.png", ".png"));
  EXPECT_EQ(ToLower("TrUe"), "true");
}

TEST(Strings, ExcerptBoundsQuotedInput) {
  EXPECT_EQ(Excerpt("short line"), "short line");
  EXPECT_EQ(Excerpt(std::string(80, 'a')), std::string(80, 'a'));
  const std::string long_line(8'000'000, 'x');
  const std::string e = Excerpt(long_line);
  EXPECT_EQ(e, std::string(80, 'x') + "... (8000000 characters)");
  EXPECT_EQ(Excerpt("abcdef", 3), "abc... (6 characters)");
}

}  // namespace
}  // namespace moslam
