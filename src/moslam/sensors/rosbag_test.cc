// ROS 1 bags written by the test with the rosbag C++ API: each colour and depth encoding, the
// association of two topics by header stamp, stereo, and every bad bag an InputError naming it.
#include "moslam/sensors/rosbag.h"

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <opencv2/imgproc.hpp>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::sensors {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

constexpr int kW = 8, kH = 6;

// A message holding `pixels` (continuous) with `encoding`, stamped `t`.
sensor_msgs::Image Message(const cv::Mat& pixels, const std::string& encoding, double t) {
  sensor_msgs::Image image;
  image.header.stamp = ros::Time(t);
  image.header.frame_id = "camera";
  image.width = static_cast<uint32_t>(pixels.cols);
  image.height = static_cast<uint32_t>(pixels.rows);
  image.encoding = encoding;
  image.step = static_cast<uint32_t>(pixels.cols * pixels.elemSize());
  image.data.assign(pixels.datastart, pixels.dataend);
  return image;
}

cv::Mat Colour(int i) {  // channel c of pixel (x, y): distinct everywhere
  cv::Mat m(kH, kW, CV_8UC3);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) m.at<cv::Vec3b>(y, x) = cv::Vec3b(i + x, 100 + y, 200 + i);
  }
  return m;
}

struct BagFile {
  moslam::testing::TempDir dir;
  std::string path = dir.path() + "/seq.bag";
};

TEST(Rosbag, Mono8IsAMonocularSequence) {
  BagFile file;
  {
    rosbag::Bag bag(file.path, rosbag::bagmode::Write);
    for (int i = 0; i < 3; ++i) {
      const cv::Mat grey(kH, kW, CV_8UC1, cv::Scalar(10 * i));
      // Written a little after their stamps, as a recorder does.
      bag.write("/cam/image", ros::Time(50.0 + 0.1 * i + 0.01),
                Message(grey, "mono8", 50.0 + 0.1 * i));
    }
  }
  RosbagReader reader(file.path, {{"/cam/image"}});
  const io::Sequence& seq = reader.sequence();
  ASSERT_EQ(seq.size(), 3u);
  EXPECT_EQ(seq.sensor, io::SensorType::kMonocular);
  EXPECT_EQ(seq.name, "seq");
  EXPECT_NEAR(seq.frames[2].timestamp, 50.2, 1e-9);
  const io::FrameImages grey = reader.Read(2, io::ColourMode::kGrey);
  EXPECT_EQ(grey.left.type(), CV_8UC1);
  EXPECT_EQ(grey.left.at<uint8_t>(3, 3), 20);
  const io::FrameImages colour = reader.Read(0, io::ColourMode::kColour);
  EXPECT_EQ(colour.left.type(), CV_8UC3);
  EXPECT_TRUE(colour.depth.empty());
}

TEST(Rosbag, RgbAndDepthAssociateByStamp) {
  BagFile file;
  {
    rosbag::Bag bag(file.path, rosbag::bagmode::Write);
    cv::Mat depth(kH, kW, CV_16UC1, cv::Scalar(1500));
    depth.at<uint16_t>(0, 0) = 0;  // no measurement
    for (int i = 0; i < 4; ++i) {
      const double t = 10.0 + 0.1 * i;
      cv::Mat rgb;
      cv::cvtColor(Colour(i), rgb, cv::COLOR_BGR2RGB);
      bag.write("/rgb", ros::Time(t), Message(rgb, "rgb8", t));
      // Depth 5 ms later; frame 2's depth is missing (the frame is left out), and a stray depth
      // message far from any colour image is ignored.
      if (i != 2) bag.write("/depth", ros::Time(t + 0.005), Message(depth, "16UC1", t + 0.005));
    }
    bag.write("/depth", ros::Time(20.0), Message(depth, "16UC1", 20.0));
  }
  RosbagReader reader(file.path, {{"/rgb", "/depth"}});
  const io::Sequence& seq = reader.sequence();
  EXPECT_EQ(seq.sensor, io::SensorType::kRgbD);
  ASSERT_EQ(seq.size(), 3u);
  EXPECT_NEAR(seq.frames[2].timestamp, 10.3, 1e-9);  // the colour image's stamp
  const io::FrameImages images = reader.Read(2, io::ColourMode::kColour);
  EXPECT_EQ(cv::norm(images.left, Colour(3), cv::NORM_INF), 0.0);  // rgb8 -> BGR
  ASSERT_EQ(images.depth.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(images.depth.at<float>(1, 1), 1.5f);  // millimetres -> metres
  EXPECT_EQ(images.depth.at<float>(0, 0), 0.0f);
}

TEST(Rosbag, MetreDepthWithNaNAndStereo) {
  BagFile file;
  {
    rosbag::Bag bag(file.path, rosbag::bagmode::Write);
    cv::Mat depth(kH, kW, CV_32FC1, cv::Scalar(2.25f));
    depth.at<float>(0, 0) = std::numeric_limits<float>::quiet_NaN();
    bag.write("/rgb", ros::Time(1.0), Message(Colour(0), "bgr8", 1.0));
    bag.write("/depth", ros::Time(1.0), Message(depth, "32FC1", 1.0));
    cv::Mat right(kH, kW, CV_8UC1, cv::Scalar(77));
    bag.write("/right", ros::Time(1.0), Message(right, "mono8", 1.0));
  }
  RosbagReader rgbd(file.path, {{"/rgb", "/depth"}});
  const io::FrameImages images = rgbd.Read(0, io::ColourMode::kGrey);
  EXPECT_EQ(images.left.type(), CV_8UC1);
  EXPECT_FLOAT_EQ(images.depth.at<float>(2, 2), 2.25f);
  EXPECT_EQ(images.depth.at<float>(0, 0), 0.0f);  // NaN: no measurement
  RosbagReader stereo(file.path, {{"/rgb", "/right"}});
  EXPECT_EQ(stereo.sequence().sensor, io::SensorType::kStereo);
  EXPECT_EQ(stereo.Read(0, io::ColourMode::kGrey).right.at<uint8_t>(0, 0), 77);
}

TEST(Rosbag, BadBagsAreErrorsNamingThem) {
  BagFile file;
  EXPECT_THAT(ErrorOf([&] { RosbagReader(file.path, {{"/rgb"}}); }),
              HasSubstr("seq.bag: no such bag file"));
  const std::string text = file.dir.Write("notes.bag", "not a bag\n");
  EXPECT_THAT(ErrorOf([&] { RosbagReader(text, {{"/rgb"}}); }),
              HasSubstr("notes.bag: cannot be read as a ROS 1 bag"));
  {
    rosbag::Bag bag(file.path, rosbag::bagmode::Write);
    bag.write("/rgb", ros::Time(1.0), Message(Colour(0), "bgr8", 1.0));
    bag.write("/info", ros::Time(1.0), sensor_msgs::CameraInfo());
    cv::Mat yuv(kH, kW, CV_8UC2, cv::Scalar(1, 2));
    bag.write("/yuv", ros::Time(1.0), Message(yuv, "yuv422", 1.0));
    sensor_msgs::Image short_data = Message(Colour(1), "bgr8", 1.0);
    short_data.data.resize(10);
    bag.write("/short", ros::Time(1.0), short_data);
    bag.write("/depth_only", ros::Time(1.0),
              Message(cv::Mat(kH, kW, CV_16UC1, cv::Scalar(1)), "16UC1", 1.0));
  }
  EXPECT_THAT(
      ErrorOf([&] { RosbagReader(file.path, {{"/nope"}}); }),
      HasSubstr("seq.bag: no message on topic /nope; the bag has: /rgb (sensor_msgs/Image)"));
  EXPECT_THAT(ErrorOf([&] {
                RosbagReader(file.path, {{"/rgb", "/info"}});
              }),
              HasSubstr("topic /info holds sensor_msgs/CameraInfo, not sensor_msgs/Image"));
  EXPECT_THAT(ErrorOf([&] { RosbagReader(file.path, {{"/yuv"}}); }),
              HasSubstr("topic /yuv, message stamped 1.000000: encoding 'yuv422'"));
  EXPECT_THAT(ErrorOf([&] { RosbagReader(file.path, {{"/short"}}); }),
              HasSubstr("does not hold its pixels"));
  EXPECT_THAT(ErrorOf([&] { RosbagReader(file.path, {{"/depth_only"}}); }),
              HasSubstr("the first topic must be an image"));
  EXPECT_THAT(ErrorOf([&] {
                RosbagReader(file.path, {{"/rgb", "/rgb"}});
              }),
              HasSubstr("the same topic twice"));
}

}  // namespace
}  // namespace moslam::sensors
