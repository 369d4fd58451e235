// `moslam run --dataset rosbag` against `--dataset tum` on the same synthetic RGB-D frames: a bag
// written with the rosbag C++ API from the TUM folder (colour as bgr8, depth as 32FC1 metres,
// converted as moslam converts the folder's PNGs) gives the same trajectory, deterministic runs.
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/Image.h>

#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/testing/shared_data.h"

namespace moslam::sensors {
namespace {

std::string Slurp(const std::string& path) {
  std::ifstream in(path);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// Runs `moslam ARGS`, its output into `log`; the exit status.
int Moslam(const std::string& args, const std::string& log) {
  const std::string command = fmt::format("'{}' {} > '{}' 2>&1", MOSLAM_BINARY, args, log);
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

sensor_msgs::Image Message(const cv::Mat& pixels, const std::string& encoding, double t) {
  sensor_msgs::Image image;
  image.header.stamp = ros::Time(t);
  image.width = static_cast<uint32_t>(pixels.cols);
  image.height = static_cast<uint32_t>(pixels.rows);
  image.encoding = encoding;
  image.step = static_cast<uint32_t>(pixels.cols * pixels.elemSize());
  image.data.assign(pixels.datastart, pixels.dataend);
  return image;
}

TEST(RosbagRun, BagTracksAsTheTumFolder) {
  const moslam::testing::TempDir dir;
  const std::string seq = dir.path() + "/seq", log = dir.path() + "/log.txt";
  ASSERT_EQ(Moslam(fmt::format("synth --preset w_xyz --seed 3 --frames 24 --width 320 --height "
                               "240 --out '{}'",
                               seq),
                   log),
            0)
      << Slurp(log);
  const std::string settings_path = seq + "/settings.yaml";
  const io::Sequence sequence = io::ReadDataset(seq);
  const double factor =
      io::LoadOrbSlamSettings(settings_path, io::SensorType::kRgbD).depth_map_factor;
  const std::string bag_path = dir.path() + "/seq.bag";
  {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Write);
    for (const io::FrameEntry& frame : sequence.frames) {
      const ros::Time at(frame.timestamp);
      bag.write("/camera/rgb/image_color", at,
                Message(io::LoadColourImage(frame.image_left), "bgr8", frame.timestamp));
      bag.write("/camera/depth/image", at,
                Message(io::LoadDepthImage(frame.depth, factor), "32FC1", frame.timestamp));
    }
  }
  const std::string common =
      fmt::format("--settings '{}' --deterministic --quiet --vocabulary none", settings_path);
  ASSERT_EQ(
      Moslam(fmt::format("run --dataset tum '{}' {} --out '{}/tum'", seq, common, dir.path()), log),
      0)
      << Slurp(log);
  ASSERT_EQ(Moslam(fmt::format("run --dataset rosbag '{}' --topics "
                               "/camera/rgb/image_color,/camera/depth/image {} --out '{}/bag'",
                               bag_path, common, dir.path()),
                   log),
            0)
      << Slurp(log);
  const std::string from_tum = Slurp(dir.path() + "/tum/CameraTrajectory.txt");
  const std::string from_bag = Slurp(dir.path() + "/bag/CameraTrajectory.txt");
  EXPECT_GT(std::count(from_tum.begin(), from_tum.end(), '\n'), 20);
  EXPECT_EQ(from_bag, from_tum);  // stamps (6 decimals) and poses (9), line for line
}

}  // namespace
}  // namespace moslam::sensors
