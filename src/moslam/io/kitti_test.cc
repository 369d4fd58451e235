#include "moslam/io/kitti.h"

#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/image.h"
#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;
using test::ErrorOf;
using test::KittiCalibText;
using test::MakeKittiFolder;
using test::WriteImage;
using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(ReadKitti, ReadsAStereoSequence) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 3, /*stereo=*/true);
  const Sequence seq = ReadKitti(dir.path());
  EXPECT_EQ(seq.sensor, SensorType::kStereo);
  ASSERT_EQ(seq.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(seq.frames[i].index, i);
    EXPECT_NEAR(seq.frames[i].timestamp, 0.1 * i, 1e-12);
    EXPECT_EQ(seq.frames[i].image_left, dir.path() + fmt::format("/image_0/{:06d}.png", i));
    EXPECT_EQ(seq.frames[i].image_right, dir.path() + fmt::format("/image_1/{:06d}.png", i));
    EXPECT_TRUE(seq.frames[i].depth.empty());
  }
  ASSERT_TRUE(seq.calibration.has_value());
  const SequenceCalibration& c = *seq.calibration;
  EXPECT_DOUBLE_EQ(c.camera.fx, 20.0);
  EXPECT_DOUBLE_EQ(c.camera.fy, 20.0);
  EXPECT_DOUBLE_EQ(c.camera.cx, 9.5);
  EXPECT_DOUBLE_EQ(c.camera.cy, 4.5);
  EXPECT_EQ(c.camera.width, 20);  // from the first image
  EXPECT_EQ(c.camera.height, 10);
  EXPECT_TRUE(c.camera.distortion.IsZero());
  EXPECT_DOUBLE_EQ(c.bf, 10.0);
  EXPECT_DOUBLE_EQ(c.baseline(), 0.5);
  ASSERT_TRUE(seq.ground_truth_path.has_value());
  EXPECT_EQ(*seq.ground_truth_path, dir.path() + "/poses.txt");
}

TEST(ReadKitti, MissingRightImagesMeanMonocular) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 2, /*stereo=*/false);
  const Sequence seq = ReadKitti(dir.path());
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  EXPECT_TRUE(seq.frames[1].image_right.empty());
  EXPECT_DOUBLE_EQ(seq.calibration->bf, 0.0);
}

TEST(ReadKitti, MonocularOptionIgnoresTheRightCamera) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 2, /*stereo=*/true);
  KittiOptions options;
  options.monocular = true;
  const Sequence seq = ReadKitti(dir.path(), options);
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  EXPECT_TRUE(seq.frames[0].image_right.empty());
}

TEST(ReadKitti, ColourPairUsesImage2And3AndP2P3) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 2, /*stereo=*/false);
  for (int i = 0; i < 2; ++i) {
    WriteImage(dir, fmt::format("image_2/{:06d}.png", i), 20, 10, CV_8UC3);
    WriteImage(dir, fmt::format("image_3/{:06d}.png", i), 20, 10, CV_8UC3);
  }
  KittiOptions options;
  options.colour = true;
  const Sequence seq = ReadKitti(dir.path(), options);
  EXPECT_EQ(seq.sensor, SensorType::kStereo);
  EXPECT_EQ(seq.frames[1].image_left, dir.path() + "/image_2/000001.png");
  EXPECT_EQ(seq.frames[1].image_right, dir.path() + "/image_3/000001.png");
  // P2(0,3) = 1, P3(0,3) = -9.5: bf = 10.5 relative to P2, not P3's -9.5 alone.
  EXPECT_DOUBLE_EQ(seq.calibration->bf, 10.5);
}

TEST(ReadKitti, PosesPathOption) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 2, true);
  fs::remove(dir.path() + "/poses.txt");
  EXPECT_FALSE(ReadKitti(dir.path()).ground_truth_path.has_value());
  KittiOptions options;
  options.poses_path = dir.Write("gt/06.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_EQ(*ReadKitti(dir.path(), options).ground_truth_path, options.poses_path);
  options.poses_path = dir.path() + "/gt/07.txt";
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path(), options); }),
              AllOf(HasSubstr("gt/07.txt"), HasSubstr("not found")));
}

TEST(ReadKittiCalibration, LabelledAndUnlabelledLines) {
  testing::TempDir dir;
  const KittiCalibration labelled = ReadKittiCalibration(dir.Write("a.txt", KittiCalibText(true)));
  const KittiCalibration plain = ReadKittiCalibration(dir.Write("b.txt", KittiCalibText(false)));
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(labelled.P[i].has_value());
    ASSERT_TRUE(plain.P[i].has_value());
    EXPECT_EQ(*labelled.P[i], *plain.P[i]);
  }
  EXPECT_DOUBLE_EQ((*plain.P[1])(0, 3), -10.0);  // row-major
  EXPECT_DOUBLE_EQ((*plain.P[1])(1, 2), 4.5);
  EXPECT_DOUBLE_EQ((*plain.P[3])(2, 2), 1.0);
  const KittiCalibration two =
      ReadKittiCalibration(dir.Write("c.txt",
                                     "P0: 1 0 1 0 0 1 1 0 0 0 1 0\nR0_rect: 1 0 0 0 1 0 0 0 1\n"
                                     "Tr_velo_to_cam: 1 0 0 0 0 1 0 0 0 0 1 0\n"));
  EXPECT_TRUE(two.P[0].has_value());
  EXPECT_FALSE(two.P[1].has_value());
}

TEST(ReadKittiCalibration, MalformedLinesNameFileAndLine) {
  testing::TempDir dir;
  const std::string p0 = "P0: 20 0 9.5 0 0 20 4.5 0 0 0 1 0\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {p0 + "P1: 20 0 9.5 -10 0 20 4.5 0 0 0 1\n", "expected 12 values"},
      {p0 + "P1: 20 0 9.5 -10 0 20 4.5 0 0 0 1 0 7\n", "expected 12 values"},
      {p0 + "P1: 20 0 9.5 -10 0 20 4.5 0 0 zero 1 0\n", "'zero' is not a finite number"},
      {p0 + "P1: 20 0 9.5 nan 0 20 4.5 0 0 0 1 0\n", "not a finite number"},
      {p0 + "P7: 20 0 9.5 0 0 20 4.5 0 0 0 1 0\n", "unknown label 'P7:'"},
      {p0 + "P0: 20 0 9.5 0 0 20 4.5 0 0 0 1 0\n", "given twice"},
      {p0 + "20 0 9.5 -10 0 20 4.5 0 0 0 1 0\n", "unlabelled line"},
      {"20 0 9.5 0 0 20 4.5 0 0 0 1 0\nP1: 20 0 9.5 -10 0 20 4.5 0 0 0 1 0\n", "labelled line"},
  };
  for (const auto& [text, message] : cases) {
    const std::string path = dir.Write("calib.txt", text);
    EXPECT_THAT(ErrorOf([&] { ReadKittiCalibration(path); }),
                AllOf(HasSubstr(path + ":2:"), HasSubstr(message)))
        << text;
  }
  const std::string five =
      dir.Write("five.txt", KittiCalibText(false) + "1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THAT(ErrorOf([&] { ReadKittiCalibration(five); }),
              AllOf(HasSubstr(five + ":5:"), HasSubstr("more than four")));
  const std::string none = dir.Write("none.txt", "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n");
  EXPECT_THAT(ErrorOf([&] { ReadKittiCalibration(none); }), HasSubstr("no projection matrices"));
}

TEST(KittiProjection, IntrinsicsAndBf) {
  geometry::Matrix3x4d p0, p1;
  p0 << 700, 0, 600, 0, 0, 710, 180, 0, 0, 0, 1, 0;
  p1 = p0;
  p1(0, 3) = -350.0;
  const camera::PinholeOptions c = IntrinsicsFromProjection(p0);
  EXPECT_DOUBLE_EQ(c.fx, 700.0);
  EXPECT_DOUBLE_EQ(c.fy, 710.0);
  EXPECT_DOUBLE_EQ(c.cx, 600.0);
  EXPECT_DOUBLE_EQ(c.cy, 180.0);
  EXPECT_DOUBLE_EQ(StereoBfFromProjections(p0, p1), 350.0);
  EXPECT_THAT(ErrorOf([&] { StereoBfFromProjections(p1, p0); }), HasSubstr("not to the right"));
  geometry::Matrix3x4d other = p1;
  other(0, 0) = 650.0;
  EXPECT_THAT(ErrorOf([&] { StereoBfFromProjections(p0, other); }),
              HasSubstr("different intrinsics"));
  geometry::Matrix3x4d skewed = p0;
  skewed(0, 1) = 3.0;
  EXPECT_THAT(ErrorOf([&] { IntrinsicsFromProjection(skewed); }), HasSubstr("rectified form"));
  geometry::Matrix3x4d negative = p0;
  negative(0, 0) = -700.0;
  EXPECT_THAT(ErrorOf([&] { IntrinsicsFromProjection(negative); }), HasSubstr("fx"));
}

// A stereo folder of three frames whose times.txt gets `times`; `line` is the bad one.
void ExpectBadTimes(const std::string& times, const std::string& message, int line = 3) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 3, true);
  const std::string path = dir.Write("times.txt", times);
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }),
              AllOf(HasSubstr(fmt::format("{}:{}:", path, line)), HasSubstr(message)))
      << times;
}

TEST(ReadKitti, MalformedTimesNameFileAndLine) {
  ExpectBadTimes("0.0\n0.1\n0.2 0.3\n", "expected 1 fields");
  ExpectBadTimes("0.0\n0.1\n0.2s\n", "not a number");
  ExpectBadTimes("0.0\n0.1\nnan\n", "not a finite number");
  ExpectBadTimes("0.0\n0.1\n0.05\n", "does not increase");
  ExpectBadTimes("0.0\n0.1\n0.1\n", "does not increase");
  // A stamp without its image (the folder holds three frames).
  ExpectBadTimes("0.0\n0.1\n0.2\n0.3\n", "image_0/000003.png' not found", 4);
}

TEST(ReadKitti, MissingRightImageOfAStereoFrameNamesIt) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 3, true);
  fs::remove(dir.path() + "/image_1/000002.png");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }),
              AllOf(HasSubstr("times.txt:3:"), HasSubstr("image_1/000002.png' not found")));
}

TEST(ReadKitti, MissingFilesAndBadCalibrationAreNamed) {
  testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path() + "/06"); }), HasSubstr("not found"));
  MakeKittiFolder(dir, 2, true);
  fs::remove(dir.path() + "/times.txt");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), HasSubstr(dir.path() + "/times.txt"));
  dir.Write("times.txt", "0\n0.1\n");
  fs::remove(dir.path() + "/calib.txt");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), HasSubstr(dir.path() + "/calib.txt"));
  const std::string calib = dir.Write("calib.txt", "P0: 20 0 9.5 0 0 20 4.5 0 0 0 1 0\n");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), AllOf(HasSubstr(calib), HasSubstr("no P1")));
  dir.Write("calib.txt", "P0: 20 0 9.5 0 0 20 4.5 0 0 0 1 0\nP1: 20 0 9.5 10 0 20 4.5 0 0 0 1 0\n");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }),
              AllOf(HasSubstr(calib), HasSubstr("not to the right")));
  // cx beyond the 20 pixel wide images.
  dir.Write("calib.txt", "P0: 20 0 25 0 0 20 4.5 0 0 0 1 0\nP1: 20 0 25 -10 0 20 4.5 0 0 0 1 0\n");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), AllOf(HasSubstr(calib), HasSubstr("cx")));
  dir.Write("calib.txt", KittiCalibText(true));
  dir.Write("times.txt", "# no stamps\n");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), HasSubstr("lists no time stamps"));
  fs::remove_all(dir.path() + "/image_0");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), HasSubstr("image_0"));
}

TEST(ReadKitti, UnreadableFirstImageNamesTheImage) {
  testing::TempDir dir;
  MakeKittiFolder(dir, 2, true);
  const std::string broken = dir.Write("image_0/000000.png", "not a png");
  EXPECT_THAT(ErrorOf([&] { ReadKitti(dir.path()); }), HasSubstr(broken));
}

// Real data: KITTI odometry 06 (stereo) and 07 (left camera only) excerpts in /work/shared.
// Expected values are those of the files: calib.txt's P0 = [707.0912 0 601.8873 0; 0 707.0912
// 183.1104 0; 0 0 1 0] and P1(0,3) = -379.8145 -> baseline 379.8145 / 707.0912 = 0.53715 m.
TEST(ReadKittiRealData, Sequence06IsStereo) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/06_000000-000050");
  const Sequence seq = ReadKitti(folder);
  EXPECT_EQ(seq.name, "06_000000-000050");
  EXPECT_EQ(seq.sensor, SensorType::kStereo);
  ASSERT_EQ(seq.size(), 51u);
  EXPECT_DOUBLE_EQ(seq.frames[0].timestamp, 0.0);
  EXPECT_NEAR(seq.frames[1].timestamp, 0.1044989, 1e-9);
  EXPECT_NEAR(seq.frames.back().timestamp - seq.frames.front().timestamp, 5.2, 0.1);  // ~10 Hz
  ASSERT_TRUE(seq.calibration.has_value());
  const SequenceCalibration& c = *seq.calibration;
  EXPECT_NEAR(c.camera.fx, 707.0912, 1e-9);
  EXPECT_NEAR(c.camera.fy, 707.0912, 1e-9);
  EXPECT_NEAR(c.camera.cx, 601.8873, 1e-9);
  EXPECT_NEAR(c.camera.cy, 183.1104, 1e-9);
  EXPECT_EQ(c.camera.width, 1226);
  EXPECT_EQ(c.camera.height, 370);
  EXPECT_NEAR(c.bf, 379.8145, 1e-9);
  EXPECT_NEAR(c.baseline(), 0.53715, 1e-4);
  ASSERT_TRUE(seq.ground_truth_path.has_value());
  EXPECT_EQ(*seq.ground_truth_path, folder + "/poses.txt");

  const FrameImages images = LoadFrameImages(seq.frames[50], ColourMode::kGrey);
  EXPECT_EQ(images.left.type(), CV_8UC1);
  EXPECT_EQ(images.left.cols, 1226);
  EXPECT_EQ(images.right.size(), images.left.size());
}

TEST(ReadKittiRealData, Sequence07IsMonocular) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/07_000000-000159");
  const Sequence seq = ReadKitti(folder);
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  ASSERT_EQ(seq.size(), 160u);
  EXPECT_TRUE(seq.frames[159].image_right.empty());
  EXPECT_EQ(seq.frames[159].image_left, folder + "/image_0/000159.png");
  ASSERT_TRUE(seq.calibration.has_value());
  EXPECT_NEAR(seq.calibration->camera.fx, 707.0912, 1e-9);
  EXPECT_DOUBLE_EQ(seq.calibration->bf, 0.0);
  EXPECT_TRUE(seq.ground_truth_path.has_value());
  // Its calib.txt has labelled P0..P3; the colour pair's baseline follows from P2 and P3.
  const KittiCalibration calib = ReadKittiCalibration(folder + "/calib.txt");
  ASSERT_TRUE(calib.P[3].has_value());
  EXPECT_NEAR(StereoBfFromProjections(*calib.P[2], *calib.P[3]) / 707.0912, 0.5379, 1e-3);
}

}  // namespace
}  // namespace moslam::io
