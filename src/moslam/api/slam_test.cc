// The front door's checks: every bad option and frame is an InputError that says what was wrong,
// before anything reaches tracking. (Tracking itself: the Python tests run a synthetic sequence
// through it and compare with `moslam run`, python/tests/.)
#include "moslam/api/slam.h"

#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/api/segmenter.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::api {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

constexpr const char* kSettings = "configs/Synthetic_RGBD.yaml";  // 640x480

SlamOptions RgbdOptions() {
  SlamOptions options;
  options.settings = kSettings;
  options.deterministic = true;
  return options;
}

TEST(SlamOptions, NamesTheMissingFile) {
  SlamOptions options = RgbdOptions();
  options.settings = "no/such/settings.yaml";
  EXPECT_THAT(ErrorOf([&] { Slam slam(options); }), HasSubstr("no/such/settings.yaml"));
  options = RgbdOptions();
  options.vocabulary = "no/such.mvoc";
  EXPECT_THAT(ErrorOf([&] { Slam slam(options); }), HasSubstr("SlamOptions.vocabulary"));
  options = RgbdOptions();
  options.model_card = "no/such_card.yaml";
  EXPECT_THAT(ErrorOf([&] { Slam slam(options); }), HasSubstr("SlamOptions.model_card"));
  options = RgbdOptions();
  options.settings.clear();
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("SlamOptions.settings"));
}

TEST(SlamOptions, BadSettingsNameTheKey) {
  const moslam::testing::TempDir dir;
  const std::string path = dir.Write("bad.yaml", "%YAML:1.0\nCamera.fx: -3\n");
  SlamOptions options = RgbdOptions();
  options.settings = path;
  const std::string error = ErrorOf([&] { Slam slam(options); });
  EXPECT_THAT(error, HasSubstr(path));
}

TEST(Slam, RejectsFramesOfTheWrongKind) {
  Slam slam(RgbdOptions());
  const cv::Mat image(480, 640, CV_8UC3, cv::Scalar::all(0));
  const cv::Mat depth(480, 640, CV_16UC1, cv::Scalar::all(0));
  EXPECT_THAT(ErrorOf([&] { slam.TrackMonocular(0.0, image); }), HasSubstr("rgbd"));
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(0.0, cv::Mat(480, 640, CV_16UC1), depth); }),
              HasSubstr("image: expected 8-bit"));
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(0.0, cv::Mat(240, 320, CV_8UC3), depth); }),
              HasSubstr("is not the size of the settings"));
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(0.0, image, cv::Mat(480, 640, CV_8UC1)); }),
              HasSubstr("depth: expected 16-bit"));
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(0.0, image, cv::Mat(48, 64, CV_16UC1)); }),
              HasSubstr("depth:"));
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(0.0, image, depth, cv::Mat(480, 640, CV_8UC3)); }),
              HasSubstr("mask: expected 8-bit single-channel"));
  EXPECT_EQ(slam.frames(), 0);
}

TEST(Slam, TracksBlankFramesWithoutAPoseAndKeepsTimeOrder) {
  Slam slam(RgbdOptions());
  const cv::Mat image(480, 640, CV_8UC3, cv::Scalar::all(90));
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar::all(1.0f));
  const Tracked t = slam.TrackRgbD(1.0, image, depth);
  EXPECT_EQ(t.state, TrackingState::kNotInitialized);
  EXPECT_FALSE(t.T_world_cam);
  EXPECT_EQ(slam.frames(), 1);
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(0.5, image, depth); }), HasSubstr("goes back"));
  slam.Finish();
  EXPECT_THAT(ErrorOf([&] { slam.TrackRgbD(2.0, image, depth); }), HasSubstr("after Finish"));
  EXPECT_TRUE(slam.Trajectory().empty());
  EXPECT_TRUE(slam.MapPoints().empty());
}

TEST(Segmenter, NamesTheMissingCard) {
  EXPECT_THAT(ErrorOf([] { Segmenter s("no/such_card.yaml"); }), HasSubstr("no/such_card.yaml"));
}

}  // namespace
}  // namespace moslam::api
