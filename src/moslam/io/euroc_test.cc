#include "moslam/io/euroc.h"

#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;
using test::ErrorOf;
using test::MakeEurocFolder;
using test::WriteImage;
using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr long long kT0 = 1403636579763555584LL;  // the first stamp MakeEurocFolder writes

TEST(ReadEuroc, ReadsAStereoSequence) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 3, /*stereo=*/true);
  const Sequence seq = ReadEuroc(dir.path());
  EXPECT_EQ(seq.sensor, SensorType::kStereo);
  EXPECT_EQ(seq.name, fs::path(dir.path()).filename().string());
  ASSERT_EQ(seq.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const long long t = kT0 + 50000000LL * i;
    EXPECT_EQ(seq.frames[i].index, i);
    EXPECT_EQ(seq.frames[i].image_left, dir.path() + fmt::format("/mav0/cam0/data/{}.png", t));
    EXPECT_EQ(seq.frames[i].image_right, dir.path() + fmt::format("/mav0/cam1/data/{}.png", t));
  }
  // Nanoseconds -> seconds: 1403636579.763555584 s, kept to the resolution of a double (~2e-7 s).
  EXPECT_NEAR(seq.frames[0].timestamp, 1403636579.763555584, 1e-6);
  EXPECT_NEAR(seq.frames[1].timestamp - seq.frames[0].timestamp, 0.05, 1e-6);
  ASSERT_TRUE(seq.ground_truth_path.has_value());
  EXPECT_EQ(*seq.ground_truth_path, dir.path() + "/mav0/state_groundtruth_estimate0/data.csv");
  EXPECT_FALSE(seq.calibration.has_value());
}

TEST(ReadEuroc, AcceptsTheMav0FolderItself) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 2, true);
  const Sequence seq = ReadEuroc(dir.path() + "/mav0");
  EXPECT_EQ(seq.size(), 2u);
  EXPECT_EQ(seq.name, fs::path(dir.path()).filename().string());  // the sequence, not "mav0"
}

TEST(ReadEuroc, MonocularWithoutCam1OrOnRequest) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 2, /*stereo=*/false);
  EXPECT_EQ(ReadEuroc(dir.path()).sensor, SensorType::kMonocular);
  EXPECT_TRUE(ReadEuroc(dir.path()).frames[0].image_right.empty());
  testing::TempDir stereo;
  MakeEurocFolder(stereo, 2, true);
  EurocOptions options;
  options.monocular = true;
  const Sequence seq = ReadEuroc(stereo.path(), options);
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  EXPECT_TRUE(seq.frames[1].image_right.empty());
}

TEST(ReadEuroc, PairsByEqualStampsAndDropsUnpairedFrames) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 4, true);
  // cam1 lacks the second stamp; cam0 keeps it.
  const long long t1 = kT0 + 50000000LL;
  std::string cam1 = "#timestamp [ns],filename\n";
  for (int i = 0; i < 4; ++i) {
    if (i == 1) continue;
    const long long t = kT0 + 50000000LL * i;
    cam1 += fmt::format("{},{}.png\n", t, t);
  }
  dir.Write("mav0/cam1/data.csv", cam1);
  const Sequence seq = ReadEuroc(dir.path());
  ASSERT_EQ(seq.size(), 3u);
  for (const FrameEntry& f : seq.frames) {
    EXPECT_EQ(f.image_left.find(std::to_string(t1)), std::string::npos);
    EXPECT_EQ(fs::path(f.image_left).filename(), fs::path(f.image_right).filename());
  }
  EXPECT_EQ(seq.frames[2].index, 2);  // indices stay contiguous
  // No common stamp at all is an error.
  dir.Write("mav0/cam1/data.csv", fmt::format("#timestamp [ns],filename\n{},{}.png\n", t1 + 1, t1));
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path()); }), HasSubstr("no stereo frames"));
}

TEST(ReadEuroc, WindowsLineEndingsAndSpacesAreAccepted) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 2, false);
  const long long t1 = kT0 + 50000000LL;
  dir.Write(
      "mav0/cam0/data.csv",
      fmt::format("#timestamp [ns],filename\r\n{},{}.png\r\n{}, {}.png\r\n", kT0, kT0, t1, t1));
  const Sequence seq = ReadEuroc(dir.path());
  ASSERT_EQ(seq.size(), 2u);
  EXPECT_EQ(seq.frames[1].image_left, dir.path() + fmt::format("/mav0/cam0/data/{}.png", t1));
}

// cam0/data.csv with a good first line, then `bad` as line 3.
void ExpectBadCsvLine(const std::string& bad, const std::string& message) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 3, false);
  const std::string csv = dir.Write(
      "mav0/cam0/data.csv", fmt::format("#timestamp [ns],filename\n{},{}.png\n", kT0, kT0) + bad);
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path()); }),
              AllOf(HasSubstr(csv + ":3:"), HasSubstr(message)))
      << bad;
}

TEST(ReadEuroc, MalformedLinesNameFileAndLine) {
  const long long t1 = kT0 + 50000000LL;
  ExpectBadCsvLine(fmt::format("{},{}.png,extra\n", t1, t1), "expected 2 fields");
  ExpectBadCsvLine(fmt::format("{}\n", t1), "expected 2 fields");
  ExpectBadCsvLine(fmt::format("1.4036e18,{}.png\n", t1), "not a non-negative integer");
  ExpectBadCsvLine(fmt::format("nan,{}.png\n", t1), "not a non-negative integer");
  ExpectBadCsvLine(fmt::format("-5,{}.png\n", t1), "not a non-negative integer");
  ExpectBadCsvLine(fmt::format("{},{}.png\n", kT0 - 1, t1), "does not increase");
  ExpectBadCsvLine(fmt::format("{},{}.png\n", kT0, t1), "does not increase");
  ExpectBadCsvLine(fmt::format("{},missing.png\n", t1), "missing.png' not found");
}

TEST(ReadEuroc, MissingFilesAndFoldersAreNamed) {
  testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path() + "/MH_01"); }), HasSubstr("not found"));
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path()); }),
              AllOf(HasSubstr(dir.path()), HasSubstr("neither mav0/ nor cam0/")));
  MakeEurocFolder(dir, 2, true);
  fs::remove(dir.path() + "/mav0/cam1/data.csv");
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path()); }),
              AllOf(HasSubstr("mav0/cam1/data.csv"), HasSubstr("not found")));
  fs::remove(dir.path() + "/mav0/cam0/data.csv");
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path()); }), HasSubstr("mav0/cam0/data.csv"));
  dir.Write("mav0/cam0/data.csv", "#timestamp [ns],filename\n");
  EXPECT_THAT(ErrorOf([&] { ReadEuroc(dir.path()); }), HasSubstr("lists no images"));
}

TEST(ReadEuroc, GroundTruthIsOptional) {
  testing::TempDir dir;
  MakeEurocFolder(dir, 2, false);
  fs::remove_all(dir.path() + "/mav0/state_groundtruth_estimate0");
  EXPECT_FALSE(ReadEuroc(dir.path()).ground_truth_path.has_value());
}

}  // namespace
}  // namespace moslam::io
