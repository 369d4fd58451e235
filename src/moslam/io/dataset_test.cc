#include "moslam/io/dataset.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/image.h"
#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

using test::ErrorOf;
using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(SensorType, NamesRoundTrip) {
  for (SensorType s : {SensorType::kMonocular, SensorType::kStereo, SensorType::kRgbD}) {
    EXPECT_EQ(ParseSensorType(ToString(s)), s);
  }
  EXPECT_EQ(ParseSensorType("Mono"), SensorType::kMonocular);
  EXPECT_EQ(ParseSensorType("RGB-D"), SensorType::kRgbD);
  EXPECT_FALSE(ParseSensorType("lidar").has_value());
}

TEST(DatasetFormat, NamesRoundTrip) {
  for (DatasetFormat f : {DatasetFormat::kAuto, DatasetFormat::kTumRgbd, DatasetFormat::kKitti,
                          DatasetFormat::kEuroc, DatasetFormat::kImageFolder}) {
    EXPECT_EQ(ParseDatasetFormat(ToString(f)), f);
  }
  EXPECT_EQ(ParseDatasetFormat("TUM-RGBD"), DatasetFormat::kTumRgbd);
  EXPECT_EQ(ParseDatasetFormat("images"), DatasetFormat::kImageFolder);
  EXPECT_FALSE(ParseDatasetFormat("tartanair").has_value());
}

TEST(DetectDatasetFormat, RecognisesEachLayout) {
  testing::TempDir tum, kitti, euroc, folder, empty;
  test::MakeTumFolder(tum, 2);
  test::MakeKittiFolder(kitti, 2, true);
  test::MakeEurocFolder(euroc, 2, true);
  test::WriteImage(folder, "a.png", 4, 3);
  EXPECT_EQ(DetectDatasetFormat(tum.path()), DatasetFormat::kTumRgbd);
  EXPECT_EQ(DetectDatasetFormat(kitti.path()), DatasetFormat::kKitti);
  EXPECT_EQ(DetectDatasetFormat(euroc.path()), DatasetFormat::kEuroc);
  EXPECT_EQ(DetectDatasetFormat(euroc.path() + "/mav0"), DatasetFormat::kEuroc);
  EXPECT_EQ(DetectDatasetFormat(folder.path()), DatasetFormat::kImageFolder);
  EXPECT_EQ(DetectDatasetFormat(kitti.path() + "/image_0"), DatasetFormat::kImageFolder);
  EXPECT_FALSE(DetectDatasetFormat(empty.path()).has_value());
  EXPECT_FALSE(DetectDatasetFormat(empty.path() + "/missing").has_value());
}

TEST(ReadDataset, AutoDetectsAndReads) {
  testing::TempDir tum, kitti, euroc, folder;
  test::MakeTumFolder(tum, 3);
  test::MakeKittiFolder(kitti, 4, true);
  test::MakeEurocFolder(euroc, 5, false);
  test::WriteImage(folder, "a.png", 4, 3);
  test::WriteImage(folder, "b.png", 4, 3);
  EXPECT_EQ(ReadDataset(tum.path()).sensor, SensorType::kRgbD);
  EXPECT_EQ(ReadDataset(tum.path()).size(), 3u);
  EXPECT_EQ(ReadDataset(kitti.path()).sensor, SensorType::kStereo);
  EXPECT_EQ(ReadDataset(kitti.path()).size(), 4u);
  EXPECT_EQ(ReadDataset(euroc.path()).sensor, SensorType::kMonocular);
  EXPECT_EQ(ReadDataset(euroc.path()).size(), 5u);
  DatasetOptions options;
  options.image_folder_rate_hz = 4.0;
  const Sequence images = ReadDataset(folder.path(), options);
  EXPECT_EQ(images.size(), 2u);
  EXPECT_DOUBLE_EQ(images.frames[1].timestamp, 0.25);
  // The rate is required for an image folder.
  EXPECT_THAT(ErrorOf([&] { ReadDataset(folder.path()); }), HasSubstr("frame rate"));
}

TEST(ReadDataset, OptionsReachTheReaders) {
  testing::TempDir tum, kitti;
  test::MakeTumFolder(tum, 3);
  test::MakeKittiFolder(kitti, 2, true);
  DatasetOptions options;
  options.tum.max_difference = 0.001;  // depth is 5 ms off: nothing associates
  EXPECT_THAT(ErrorOf([&] { ReadDataset(tum.path(), options); }), HasSubstr("no RGB image"));
  options.kitti.monocular = true;
  EXPECT_EQ(ReadDataset(kitti.path(), options).sensor, SensorType::kMonocular);
}

TEST(ReadDataset, ExplicitFormatAndMonocularView) {
  testing::TempDir tum;
  test::MakeTumFolder(tum, 2);
  DatasetOptions options;
  options.format = DatasetFormat::kTumRgbd;
  options.monocular = true;
  const Sequence seq = ReadDataset(tum.path(), options);
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  EXPECT_TRUE(seq.frames[0].depth.empty());
  EXPECT_FALSE(seq.frames[0].image_left.empty());
  // Forcing the wrong reader gives that reader's error.
  options.format = DatasetFormat::kKitti;
  EXPECT_THAT(ErrorOf([&] { ReadDataset(tum.path(), options); }), HasSubstr("image_0"));
}

TEST(ReadDataset, UnknownLayoutsAndMissingFoldersAreErrors) {
  testing::TempDir dir;
  dir.Write("readme.txt", "nothing here");
  EXPECT_THAT(ErrorOf([&] { ReadDataset(dir.path()); }),
              AllOf(HasSubstr(dir.path()), HasSubstr("unknown data set layout")));
  EXPECT_THAT(ErrorOf([&] { ReadDataset(dir.path() + "/missing"); }),
              AllOf(HasSubstr(dir.path() + "/missing"), HasSubstr("not found")));
}

TEST(ReadDataset, EveryFrameOfEveryFormatLoadsTheSameWay) {
  testing::TempDir tum, kitti, euroc;
  test::MakeTumFolder(tum, 2);
  test::MakeKittiFolder(kitti, 2, true);
  test::MakeEurocFolder(euroc, 2, true);
  for (const std::string& path : {tum.path(), kitti.path(), euroc.path()}) {
    const Sequence seq = ReadDataset(path);
    for (const FrameEntry& frame : seq.frames) {
      const FrameImages images = LoadFrameImages(frame, ColourMode::kGrey);
      EXPECT_EQ(images.left.type(), CV_8UC1) << path;
      EXPECT_EQ(!images.right.empty(), seq.sensor == SensorType::kStereo) << path;
      EXPECT_EQ(!images.depth.empty(), seq.sensor == SensorType::kRgbD) << path;
    }
  }
}

TEST(ReadDatasetRealData, DetectsKitti) {
  MOSLAM_SHARED_OR_SKIP(folder, "data/kitti/07_000000-000159");
  EXPECT_EQ(DetectDatasetFormat(folder), DatasetFormat::kKitti);
  const Sequence seq = ReadDataset(folder);
  EXPECT_EQ(seq.sensor, SensorType::kMonocular);
  EXPECT_EQ(seq.size(), 160u);
}

}  // namespace
}  // namespace moslam::io
