#include "moslam/feature/orb_options.h"
#include "moslam/testing/error_of.h"

#include <functional>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

using ::testing::AllOf;
using ::testing::HasSubstr;

using ::moslam::testing::ErrorOf;

TEST(OrbExtractorOptions, DefaultsAreOrbSlam2sAndValid) {
  const OrbExtractorOptions options;
  EXPECT_EQ(options.num_features, 1000);
  EXPECT_DOUBLE_EQ(options.scale_factor, 1.2);
  EXPECT_EQ(options.num_levels, 8);
  EXPECT_EQ(options.ini_th_fast, 20);
  EXPECT_EQ(options.min_th_fast, 7);
  EXPECT_EQ(options.mask_dilation_px, 0);
  EXPECT_NO_THROW(options.Check());
}

TEST(OrbExtractorOptions, CheckNamesTheOptionAndItsOrbSlam2Key) {
  struct Case {
    std::function<void(OrbExtractorOptions&)> corrupt;
    std::string name;
  };
  const std::vector<Case> cases = {
      {[](OrbExtractorOptions& o) { o.num_features = 0; }, "ORBextractor.nFeatures"},
      {[](OrbExtractorOptions& o) { o.scale_factor = 1.0; }, "ORBextractor.scaleFactor"},
      {[](OrbExtractorOptions& o) { o.scale_factor = 0.8; }, "ORBextractor.scaleFactor"},
      {[](OrbExtractorOptions& o) { o.num_levels = 0; }, "ORBextractor.nLevels"},
      {[](OrbExtractorOptions& o) { o.ini_th_fast = 0; }, "ORBextractor.iniThFAST"},
      {[](OrbExtractorOptions& o) { o.ini_th_fast = 300; }, "ORBextractor.iniThFAST"},
      {[](OrbExtractorOptions& o) { o.min_th_fast = 25; }, "ORBextractor.minThFAST"},
      {[](OrbExtractorOptions& o) { o.min_th_fast = 0; }, "ORBextractor.minThFAST"},
      {[](OrbExtractorOptions& o) { o.mask_dilation_px = -1; }, "mask_dilation_px"},
      {[](OrbExtractorOptions& o) { o.cell_size_px = 5; }, "cell_size_px"},
  };
  for (const Case& c : cases) {
    OrbExtractorOptions options;
    c.corrupt(options);
    EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr(c.name));
  }
}

TEST(OrbExtractorOptions, ApplySettingsTakesTheOrbSlam2ValuesAndKeepsTheRest) {
  io::OrbExtractorOptions settings;
  settings.num_features = 2000;
  settings.ini_th_fast = 12;
  OrbExtractorOptions options;
  options.mask_dilation_px = 3;  // not an ORB-SLAM2 key: kept
  options.ApplySettings(settings);
  EXPECT_EQ(options.num_features, 2000);
  EXPECT_EQ(options.ini_th_fast, 12);
  EXPECT_EQ(options.min_th_fast, 7);
  EXPECT_EQ(options.mask_dilation_px, 3);
}

TEST(OrbExtractorOptions, LoadsFromTheShippedKittiSettings) {
  const io::OrbSlamSettings settings =
      io::LoadOrbSlamSettings("configs/KITTI04-12.yaml", io::SensorType::kStereo);
  OrbExtractorOptions options;
  options.ApplySettings(settings.orb);
  EXPECT_EQ(options.num_features, 2000);
  EXPECT_NO_THROW(options.Check());
}

}  // namespace
}  // namespace moslam::feature
