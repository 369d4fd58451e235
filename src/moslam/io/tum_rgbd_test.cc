#include "moslam/io/tum_rgbd.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <tuple>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

using test::ErrorOf;
using test::MakeTumFolder;
using test::WriteImage;
using ::testing::AllOf;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using Pairs = std::vector<std::pair<size_t, size_t>>;

// associate.py written out literally (all pairs, sort the tuples, greedy, sort by first stamp):
// the reference the indexed implementation must reproduce.
Pairs AssociateReference(const std::vector<double>& first, const std::vector<double>& second,
                         double offset, double max_difference) {
  std::vector<std::tuple<double, double, double, size_t, size_t>> candidates;
  for (size_t i = 0; i < first.size(); ++i) {
    for (size_t j = 0; j < second.size(); ++j) {
      const double d = std::abs(first[i] - (second[j] + offset));
      if (d < max_difference) candidates.emplace_back(d, first[i], second[j], i, j);
    }
  }
  std::sort(candidates.begin(), candidates.end());
  std::vector<bool> used_first(first.size()), used_second(second.size());
  Pairs matches;
  for (const auto& [d, a, b, i, j] : candidates) {
    if (used_first[i] || used_second[j]) continue;
    used_first[i] = used_second[j] = true;
    matches.emplace_back(i, j);
  }
  std::sort(matches.begin(), matches.end(),
            [&](const auto& x, const auto& y) { return first[x.first] < first[y.first]; });
  return matches;
}

TEST(AssociateTimestamps, PicksTheSmallestDifferenceFirstNotTheNearestNeighbour) {
  // Seen from first[0] = 0.0, second[0] = 0.010 is the only candidate; but first[1] = 0.012 is
  // closer to it (0.002 < 0.010), so associate.py gives it to first[1] and first[0] stays alone.
  EXPECT_THAT(AssociateTimestamps({0.0, 0.012}, {0.010}, 0.0, 0.02),
              ElementsAre(std::make_pair(size_t{1}, size_t{0})));
}

TEST(AssociateTimestamps, UsesEachStampOnce) {
  const Pairs pairs = AssociateTimestamps({1.0, 1.001, 1.002}, {1.0012}, 0.0, 0.02);
  EXPECT_THAT(pairs,
              ElementsAre(std::make_pair(size_t{1}, size_t{0})));  // 0.0002 beats 0.0008 and 0.0012
  const Pairs reverse = AssociateTimestamps({1.0012}, {1.0, 1.001, 1.002}, 0.0, 0.02);
  EXPECT_THAT(reverse, ElementsAre(std::make_pair(size_t{0}, size_t{1})));
}

TEST(AssociateTimestamps, MaxDifferenceIsAStrictBound) {
  // Binary-exact stamps so that the difference is exactly the bound.
  EXPECT_TRUE(AssociateTimestamps({0.0}, {0.25}, 0.0, 0.25).empty());
  EXPECT_EQ(AssociateTimestamps({0.0}, {0.25}, 0.0, 0.25 + 1e-9).size(), 1u);
  EXPECT_TRUE(AssociateTimestamps({0.0}, {0.03}, 0.0, 0.02).empty());
}

TEST(AssociateTimestamps, OffsetIsAddedToTheSecondStamps) {
  EXPECT_TRUE(AssociateTimestamps({10.0}, {9.5}, 0.0, 0.02).empty());
  EXPECT_EQ(AssociateTimestamps({10.0}, {9.5}, 0.5, 0.02).size(), 1u);
  EXPECT_TRUE(AssociateTimestamps({10.0}, {9.5}, -0.5, 0.02).empty());
}

TEST(AssociateTimestamps, TiesGoToTheEarlierStamp) {
  // |1 - 0.75| == |1 - 1.25| exactly; Python's tuple order picks the smaller second stamp.
  EXPECT_THAT(AssociateTimestamps({1.0}, {0.75, 1.25}, 0.0, 0.5),
              ElementsAre(std::make_pair(size_t{0}, size_t{0})));
  EXPECT_THAT(AssociateTimestamps({1.25, 0.75}, {1.0}, 0.0, 0.5),
              ElementsAre(std::make_pair(size_t{1}, size_t{0})));
}

TEST(AssociateTimestamps, ResultIsSortedByTheFirstStamp) {
  // Accepted in the order (2,2), (0,0), (1,1) by difference; returned by first stamp.
  const Pairs pairs = AssociateTimestamps({1.0, 2.0, 3.0}, {1.01, 2.015, 3.001}, 0.0, 0.02);
  EXPECT_THAT(
      pairs, ElementsAre(std::make_pair(size_t{0}, size_t{0}), std::make_pair(size_t{1}, size_t{1}),
                         std::make_pair(size_t{2}, size_t{2})));
}

TEST(AssociateTimestamps, MatchesTheLiteralAlgorithmOnRandomStreams) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  std::bernoulli_distribution drop(0.15);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> rgb, depth;
    for (int k = 0; k < 300; ++k) {
      if (!drop(rng)) rgb.push_back(k / 30.0 + jitter(rng) * 0.1);
      if (!drop(rng)) depth.push_back(k / 30.0 + 0.01 + jitter(rng));
    }
    std::sort(rgb.begin(), rgb.end());
    std::sort(depth.begin(), depth.end());
    for (double offset : {0.0, -0.01}) {
      const Pairs expected = AssociateReference(rgb, depth, offset, 0.02);
      EXPECT_EQ(AssociateTimestamps(rgb, depth, offset, 0.02), expected) << trial;
      EXPECT_GT(expected.size(), 100u);
    }
  }
}

TEST(ReadTumRgbd, ReadsASequenceFolder) {
  testing::TempDir dir;
  MakeTumFolder(dir, 4);
  const Sequence seq = ReadTumRgbd(dir.path());
  EXPECT_EQ(seq.sensor, SensorType::kRgbD);
  EXPECT_EQ(seq.root, dir.path());
  EXPECT_FALSE(seq.name.empty());
  EXPECT_EQ(seq.name, std::filesystem::path(dir.path()).filename().string());
  ASSERT_EQ(seq.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    const FrameEntry& f = seq.frames[i];
    EXPECT_EQ(f.index, i);
    EXPECT_NEAR(f.timestamp, 1.0 + 0.1 * i, 1e-9);  // the RGB stamp
    EXPECT_EQ(f.image_left, dir.path() + "/" + fmt::format("rgb/{:.6f}.png", 1.0 + 0.1 * i));
    EXPECT_EQ(f.depth, dir.path() + "/" + fmt::format("depth/{:.6f}.png", 1.005 + 0.1 * i));
    EXPECT_TRUE(f.image_right.empty());
  }
  ASSERT_TRUE(seq.ground_truth_path.has_value());
  EXPECT_EQ(*seq.ground_truth_path, dir.path() + "/groundtruth.txt");
  EXPECT_FALSE(seq.calibration.has_value());
}

TEST(ReadTumRgbd, OptionsChangeTheAssociation) {
  testing::TempDir dir;
  MakeTumFolder(dir, 3);  // depth is 5 ms after rgb
  TumRgbdOptions tight;
  tight.max_difference = 0.004;
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path(), tight); }),
              AllOf(HasSubstr(dir.path()), HasSubstr("no RGB image has a depth image")));
  tight.offset = -0.005;  // moves the depth stamps back onto the rgb ones
  EXPECT_EQ(ReadTumRgbd(dir.path(), tight).size(), 3u);
  TumRgbdOptions bad;
  bad.max_difference = 0.0;
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path(), bad); }), HasSubstr("max_difference"));
  bad.max_difference = std::nan("");
  EXPECT_THROW(bad.Check(), InputError);
}

TEST(ReadTumRgbd, GroundTruthIsOptional) {
  testing::TempDir dir;
  MakeTumFolder(dir, 2);
  std::filesystem::remove(dir.path() + "/groundtruth.txt");
  EXPECT_FALSE(ReadTumRgbd(dir.path()).ground_truth_path.has_value());
}

TEST(ReadTumRgbd, ReadsAnAssociationsFile) {
  testing::TempDir dir;
  MakeTumFolder(dir, 3);
  const std::string assoc = dir.Write("associations.txt",
                                      "1.000000 rgb/1.000000.png 1.005000 depth/1.005000.png\n"
                                      "\n"
                                      "1.200000 rgb/1.200000.png 1.205000 depth/1.205000.png\n");
  TumRgbdOptions options;
  options.associations_path = assoc;
  const Sequence seq = ReadTumRgbd(dir.path(), options);
  ASSERT_EQ(seq.size(), 2u);
  EXPECT_DOUBLE_EQ(seq.frames[1].timestamp, 1.2);
  EXPECT_EQ(seq.frames[1].index, 1);
  EXPECT_EQ(seq.frames[1].depth, dir.path() + "/depth/1.205000.png");
}

TEST(ReadTumRgbd, BadAssociationsFilesNameFileAndLine) {
  testing::TempDir dir;
  MakeTumFolder(dir, 3);
  TumRgbdOptions options;
  const std::string good = "1.000000 rgb/1.000000.png 1.005000 depth/1.005000.png\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {good + "1.1 rgb/1.100000.png 1.105\n", "expected 4 fields"},
      {good + "abc rgb/1.100000.png 1.105 depth/1.105000.png\n", "not a number"},
      {good + "1.1 rgb/1.100000.png nan depth/1.105000.png\n", "not a finite number"},
      {good + "0.9 rgb/1.100000.png 1.105 depth/1.105000.png\n", "does not increase"},
      {good + "1.1 rgb/1.100000.png 1.105 depth/9.png\n", "depth/9.png' not found"},
  };
  for (const auto& [text, message] : cases) {
    options.associations_path = dir.Write("assoc.txt", text);
    EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path(), options); }),
                AllOf(HasSubstr(options.associations_path + ":2:"), HasSubstr(message)));
  }
  options.associations_path = dir.Write("empty.txt", "# nothing\n");
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path(), options); }), HasSubstr("lists no frames"));
  options.associations_path = dir.path() + "/missing.txt";
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path(), options); }),
              AllOf(HasSubstr("missing.txt"), HasSubstr("not found")));
}

// Issue 31: a message quoted the whole offending line, megabytes for a file without newlines.
TEST(ReadTumRgbd, HugeBadLinesAreQuotedAsExcerpts) {
  testing::TempDir dir;
  MakeTumFolder(dir, 3);
  TumRgbdOptions options;
  const std::string huge(8'000'000, '7');
  for (const std::string& line : {"1.0 " + huge + " 2.0\n", huge + "x rgb/a.png 1.0 depth/b.png\n",
                                  "1.0 rgb/" + huge + ".png 1.005 depth/1.005000.png\n"}) {
    options.associations_path = dir.Write("assoc.txt", line);
    const std::string message = ErrorOf([&] { ReadTumRgbd(dir.path(), options); });
    EXPECT_THAT(message, AllOf(HasSubstr(options.associations_path + ":1:"), HasSubstr("...")));
    EXPECT_LT(message.size(), 1000u) << message.substr(0, 200);
  }
}

TEST(ReadTumFileList, ReadsStampsAndResolvesPaths) {
  testing::TempDir dir;
  MakeTumFolder(dir, 3);
  const auto files = ReadTumFileList(dir.path() + "/depth.txt");
  ASSERT_EQ(files.size(), 3u);
  EXPECT_EQ(files[0].line, 5);  // three comment lines and a blank one come first
  EXPECT_DOUBLE_EQ(files[2].timestamp, 1.205);
  EXPECT_EQ(files[2].path, dir.path() + "/depth/1.205000.png");
}

// Writes rgb.txt with a good first entry followed by `bad_line` (line 3) and expects an error
// naming rgb.txt:3 with `message`.
void ExpectBadRgbLine(const std::string& bad_line, const std::string& message) {
  testing::TempDir dir;
  MakeTumFolder(dir, 3);
  const std::string rgb = dir.Write("rgb.txt", "# header\n1.000000 rgb/1.000000.png\n" + bad_line);
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path()); }),
              AllOf(HasSubstr(rgb + ":3:"), HasSubstr(message)))
      << bad_line;
}

TEST(ReadTumRgbd, MalformedListLinesNameFileAndLine) {
  ExpectBadRgbLine("1.100000 rgb/1.100000.png extra\n", "expected 2 fields");
  ExpectBadRgbLine("1.100000\n", "expected 2 fields");
  ExpectBadRgbLine("1.1x rgb/1.100000.png\n", "not a number");
  ExpectBadRgbLine("nan rgb/1.100000.png\n", "not a finite number");
  ExpectBadRgbLine("inf rgb/1.100000.png\n", "not a finite number");
  ExpectBadRgbLine("0.5 rgb/1.100000.png\n", "does not increase");
  ExpectBadRgbLine("1.0 rgb/1.100000.png\n", "does not increase");  // repeated stamp
  ExpectBadRgbLine("1.1 rgb/missing.png\n", "rgb/missing.png' not found");
}

TEST(ReadTumRgbd, MissingFilesAndFoldersAreNamed) {
  testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path() + "/nothing"); }),
              AllOf(HasSubstr(dir.path() + "/nothing"), HasSubstr("not found")));
  MakeTumFolder(dir, 2);
  std::filesystem::remove(dir.path() + "/depth.txt");
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path()); }),
              AllOf(HasSubstr(dir.path() + "/depth.txt"), HasSubstr("not found")));
  dir.Write("depth.txt", "# only comments\n\n");
  EXPECT_THAT(ErrorOf([&] { ReadTumRgbd(dir.path()); }),
              AllOf(HasSubstr("depth.txt"), HasSubstr("lists no images")));
}

}  // namespace
}  // namespace moslam::io
