// Test support for the io module: small synthetic data sets written into a TempDir, and a helper
// that returns the message of an expected InputError. Used by io's *_test.cc only.
#pragma once

#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::io::test {

using ::moslam::testing::ErrorOf;

// Writes a `cols` x `rows` image of `type` filled with `value` to dir/name; returns its path.
inline std::string WriteImage(const testing::TempDir& dir, const std::string& name, int cols,
                              int rows, int type = CV_8UC1, double value = 128.0) {
  const std::string path = dir.Write(name, "");  // creates parent folders
  const cv::Mat image(rows, cols, type, cv::Scalar::all(value));
  EXPECT_TRUE(cv::imwrite(path, image)) << path;
  return path;
}

// TUM RGB-D folder: rgb.txt with stamps 1.00, 1.10, ... and depth.txt 0.005 s later, both with
// TUM's comment header, a blank line, 8x6 images, and groundtruth.txt.
inline void MakeTumFolder(const testing::TempDir& dir, int frames) {
  std::string rgb = "# color images\n# file: 'rgbd_dataset_test.bag'\n# timestamp filename\n";
  std::string depth = "# depth maps\n# file: 'rgbd_dataset_test.bag'\n# timestamp filename\n\n";
  for (int i = 0; i < frames; ++i) {
    const std::string t_rgb = fmt::format("{:.6f}", 1.0 + 0.1 * i);
    const std::string t_depth = fmt::format("{:.6f}", 1.005 + 0.1 * i);
    rgb += fmt::format("{} rgb/{}.png\n", t_rgb, t_rgb);
    depth += fmt::format("{} depth/{}.png\n", t_depth, t_depth);
    WriteImage(dir, fmt::format("rgb/{}.png", t_rgb), 8, 6, CV_8UC3);
    WriteImage(dir, fmt::format("depth/{}.png", t_depth), 8, 6, CV_16UC1, 5000.0);
  }
  dir.Write("rgb.txt", rgb);
  dir.Write("depth.txt", depth);
  dir.Write("groundtruth.txt", "# timestamp tx ty tz qx qy qz qw\n1.0 0 0 0 0 0 0 1\n");
}

// KITTI calib.txt rows for 20x10 images: fx = fy = 20, cx = 9.5, cy = 4.5, stereo baseline
// 0.5 m (P1(0,3) = -fx * 0.5 = -10); P2/P3 are the colour pair, offset like KITTI's.
inline std::string KittiCalibText(bool labels) {
  const std::vector<std::string> rows = {
      "20 0 9.5 0 0 20 4.5 0 0 0 1 0",
      "20 0 9.5 -10 0 20 4.5 0 0 0 1 0",
      "20 0 9.5 1 0 20 4.5 0 0 0 1 0",
      "20 0 9.5 -9.5 0 20 4.5 0 0 0 1 0",
  };
  std::string text;
  for (size_t i = 0; i < rows.size(); ++i) {
    text += (labels ? fmt::format("P{}: ", i) : std::string()) + rows[i] + "\n";
  }
  if (labels) text += "Tr: 1 0 0 0 0 1 0 0 0 0 1 0\n";
  return text;
}

// KITTI odometry folder with `frames` frames at 10 Hz: image_0 (and image_1 when `stereo`).
inline void MakeKittiFolder(const testing::TempDir& dir, int frames, bool stereo) {
  std::string times;
  for (int i = 0; i < frames; ++i) {
    times += fmt::format("{:e}\n", 0.1 * i);
    WriteImage(dir, fmt::format("image_0/{:06d}.png", i), 20, 10);
    if (stereo) WriteImage(dir, fmt::format("image_1/{:06d}.png", i), 20, 10);
  }
  dir.Write("times.txt", times);
  dir.Write("calib.txt", KittiCalibText(true));
  dir.Write("poses.txt", "1 0 0 0 0 1 0 0 0 0 1 0\n");
}

// EuRoC folder: <dir>/mav0/cam0 (and cam1 when `stereo`) with `frames` images 50 ms apart
// starting at 1403636579763555584 ns, and a ground-truth csv.
inline void MakeEurocFolder(const testing::TempDir& dir, int frames, bool stereo) {
  const long long t0 = 1403636579763555584LL;
  std::string csv = "#timestamp [ns],filename\n";
  for (int i = 0; i < frames; ++i) {
    const long long t = t0 + 50000000LL * i;
    csv += fmt::format("{},{}.png\n", t, t);
    WriteImage(dir, fmt::format("mav0/cam0/data/{}.png", t), 8, 6);
    if (stereo) WriteImage(dir, fmt::format("mav0/cam1/data/{}.png", t), 8, 6);
  }
  dir.Write("mav0/cam0/data.csv", csv);
  if (stereo) dir.Write("mav0/cam1/data.csv", csv);
  dir.Write("mav0/state_groundtruth_estimate0/data.csv", "#timestamp,p_RS_R_x [m]\n");
}

}  // namespace moslam::io::test
