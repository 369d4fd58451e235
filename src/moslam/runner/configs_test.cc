// Every settings file in configs/ loads for the sensors it is meant for (tests run from the
// repository root), and the KITTI stereo files hold ORB-SLAM2's values.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "moslam/io/orbslam_settings.h"

namespace moslam::io {
namespace {

namespace fs = std::filesystem;

// The sensor a file is written for, by the naming of configs/: TUM* are RGB-D, *_mono monocular,
// the rest (KITTI, EuRoC) stereo.
SensorType SensorOf(const std::string& name) {
  if (name.find("_mono") != std::string::npos) return SensorType::kMonocular;
  if (name.rfind("TUM", 0) == 0) return SensorType::kRgbD;
  return SensorType::kStereo;
}

TEST(ConfigsTest, EveryFileLoadsForItsSensorAndMonocular) {
  std::vector<std::string> files;
  for (const auto& entry : fs::directory_iterator("configs")) {
    if (entry.path().extension() == ".yaml") files.push_back(entry.path().string());
  }
  ASSERT_GE(files.size(), 8u) << "configs/ not found from " << fs::current_path();
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    const SensorType sensor = SensorOf(fs::path(path).filename().string());
    EXPECT_NO_THROW(LoadOrbSlamSettings(path, sensor));
    // Every file also serves a monocular run (ORB-SLAM2 uses its TUM files for both).
    EXPECT_NO_THROW(LoadOrbSlamSettings(path, SensorType::kMonocular));
  }
}

TEST(ConfigsTest, KittiStereoFilesHaveOrbSlam2Values) {
  struct Expected {
    const char* path;
    double fx, cx, cy, bf;
  };
  const Expected files[] = {
      {"configs/KITTI00-02.yaml", 718.856, 607.1928, 185.2157, 386.1448},
      {"configs/KITTI03.yaml", 721.5377, 609.5593, 172.854, 387.5744},
      {"configs/KITTI04-12.yaml", 707.0912, 601.8873, 183.1104, 379.8145},
  };
  for (const Expected& e : files) {
    SCOPED_TRACE(e.path);
    const OrbSlamSettings s = LoadOrbSlamSettings(e.path, SensorType::kStereo);
    EXPECT_DOUBLE_EQ(s.camera.fx, e.fx);
    EXPECT_DOUBLE_EQ(s.camera.fy, e.fx);
    EXPECT_DOUBLE_EQ(s.camera.cx, e.cx);
    EXPECT_DOUBLE_EQ(s.camera.cy, e.cy);
    EXPECT_DOUBLE_EQ(s.bf, e.bf);
    EXPECT_DOUBLE_EQ(s.fps, 10.0);
    EXPECT_TRUE(s.rgb);
    EXPECT_DOUBLE_EQ(s.th_depth, 35.0);
    EXPECT_EQ(s.orb.num_features, 2000);
    EXPECT_DOUBLE_EQ(s.orb.scale_factor, 1.2);
    EXPECT_EQ(s.orb.num_levels, 8);
    EXPECT_EQ(s.orb.ini_th_fast, 20);
    EXPECT_EQ(s.orb.min_th_fast, 7);
  }
}

}  // namespace
}  // namespace moslam::io
