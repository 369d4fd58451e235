#include "moslam/io/image.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/io/io_test_util.h"

namespace moslam::io {
namespace {

using test::ErrorOf;
using test::WriteImage;
using ::testing::AllOf;
using ::testing::HasSubstr;

TEST(LoadImage, GreyAndColourConversions) {
  testing::TempDir dir;
  const std::string colour = WriteImage(dir, "c.png", 8, 6, CV_8UC3, 100.0);
  const std::string grey = WriteImage(dir, "g.pgm", 5, 4, CV_8UC1, 42.0);
  const cv::Mat a = LoadGreyImage(colour);
  EXPECT_EQ(a.type(), CV_8UC1);
  EXPECT_EQ(a.cols, 8);
  EXPECT_EQ(a.rows, 6);
  EXPECT_EQ(a.at<uint8_t>(2, 3), 100);
  const cv::Mat b = LoadColourImage(grey);
  EXPECT_EQ(b.type(), CV_8UC3);
  EXPECT_EQ(b.at<cv::Vec3b>(1, 1), cv::Vec3b(42, 42, 42));
  EXPECT_EQ(LoadImage(grey, ColourMode::kGrey).type(), CV_8UC1);
  EXPECT_EQ(LoadImage(grey, ColourMode::kColour).type(), CV_8UC3);
}

TEST(LoadImage, MissingFileIsAnErrorNamingIt) {
  testing::TempDir dir;
  const std::string path = dir.path() + "/nope.png";
  EXPECT_THAT(ErrorOf([&] { LoadGreyImage(path); }),
              AllOf(HasSubstr(path), HasSubstr("not found")));
  EXPECT_THAT(ErrorOf([&] { LoadColourImage(path); }), HasSubstr(path));
  EXPECT_THAT(ErrorOf([&] { LoadDepthImage(path); }), HasSubstr(path));
  EXPECT_THAT(ErrorOf([&] { LoadGreyImage(dir.path()); }), HasSubstr("not found"));  // a folder
}

TEST(LoadImage, UndecodableFileIsAnErrorNamingIt) {
  testing::TempDir dir;
  const std::string path = dir.Write("broken.png", "this is not a PNG file");
  EXPECT_THAT(ErrorOf([&] { LoadGreyImage(path); }),
              AllOf(HasSubstr(path), HasSubstr("cannot be")));
  EXPECT_THAT(ErrorOf([&] { LoadDepthImage(path); }), HasSubstr(path));
}

TEST(LoadDepthImage, ConvertsSixteenBitToMetres) {
  testing::TempDir dir;
  cv::Mat raw(2, 3, CV_16UC1);
  raw.at<uint16_t>(0, 0) = 0;
  raw.at<uint16_t>(0, 1) = 5000;
  raw.at<uint16_t>(0, 2) = 10000;
  raw.at<uint16_t>(1, 0) = 1;
  raw.at<uint16_t>(1, 1) = 65535;
  raw.at<uint16_t>(1, 2) = 2500;
  const std::string path = dir.Write("d.png", "");
  ASSERT_TRUE(cv::imwrite(path, raw));

  const cv::Mat depth = LoadDepthImage(path);
  ASSERT_EQ(depth.type(), CV_32FC1);
  EXPECT_EQ(depth.at<float>(0, 0), 0.0f);  // invalid stays invalid
  EXPECT_FLOAT_EQ(depth.at<float>(0, 1), 1.0f);
  EXPECT_FLOAT_EQ(depth.at<float>(0, 2), 2.0f);
  EXPECT_FLOAT_EQ(depth.at<float>(1, 0), 1.0f / 5000.0f);
  EXPECT_FLOAT_EQ(depth.at<float>(1, 1), 65535.0f / 5000.0f);
  EXPECT_FLOAT_EQ(depth.at<float>(1, 2), 0.5f);
  EXPECT_FLOAT_EQ(LoadDepthImage(path, 1000.0).at<float>(0, 1), 5.0f);
}

TEST(LoadDepthImage, RejectsEightBitImagesAndBadFactors) {
  testing::TempDir dir;
  const std::string eight = WriteImage(dir, "d8.png", 4, 4, CV_8UC1, 10.0);
  EXPECT_THAT(ErrorOf([&] { LoadDepthImage(eight); }),
              AllOf(HasSubstr(eight), HasSubstr("16-bit")));
  const std::string colour = WriteImage(dir, "d16c.png", 4, 4, CV_16UC3, 10.0);
  EXPECT_THAT(ErrorOf([&] { LoadDepthImage(colour); }), HasSubstr("single-channel"));
  const std::string good = WriteImage(dir, "d16.png", 4, 4, CV_16UC1, 10.0);
  EXPECT_THAT(ErrorOf([&] { LoadDepthImage(good, 0.0); }), HasSubstr("depth factor"));
  EXPECT_THAT(ErrorOf([&] { LoadDepthImage(good, -5000.0); }), HasSubstr("depth factor"));
}

TEST(LoadFrameImages, LoadsWhatTheFrameLists) {
  testing::TempDir dir;
  FrameEntry mono;
  mono.image_left = WriteImage(dir, "l.png", 8, 6);
  const FrameImages m = LoadFrameImages(mono, ColourMode::kGrey);
  EXPECT_FALSE(m.left.empty());
  EXPECT_TRUE(m.right.empty());
  EXPECT_TRUE(m.depth.empty());

  FrameEntry stereo = mono;
  stereo.image_right = WriteImage(dir, "r.png", 8, 6);
  const FrameImages s = LoadFrameImages(stereo, ColourMode::kGrey);
  EXPECT_EQ(s.right.size(), s.left.size());

  FrameEntry rgbd = mono;
  rgbd.depth = WriteImage(dir, "d.png", 8, 6, CV_16UC1, 2500.0);
  const FrameImages d = LoadFrameImages(rgbd, ColourMode::kColour);
  EXPECT_EQ(d.left.type(), CV_8UC3);
  EXPECT_FLOAT_EQ(d.depth.at<float>(3, 3), 0.5f);
  EXPECT_FLOAT_EQ(LoadFrameImages(rgbd, ColourMode::kGrey, 1000.0).depth.at<float>(0, 0), 2.5f);
}

TEST(LoadFrameImages, MissingOrMismatchedImagesNameTheFile) {
  testing::TempDir dir;
  FrameEntry frame;
  frame.image_left = WriteImage(dir, "l.png", 8, 6);
  frame.image_right = dir.path() + "/missing_right.png";
  EXPECT_THAT(ErrorOf([&] { LoadFrameImages(frame, ColourMode::kGrey); }),
              HasSubstr("missing_right.png"));
  frame.image_right = WriteImage(dir, "small_right.png", 4, 6);
  EXPECT_THAT(ErrorOf([&] { LoadFrameImages(frame, ColourMode::kGrey); }),
              AllOf(HasSubstr("small_right.png"), HasSubstr("4x6"), HasSubstr("8x6")));
  frame.image_right.clear();
  frame.depth = WriteImage(dir, "big_depth.png", 16, 12, CV_16UC1);
  EXPECT_THAT(ErrorOf([&] { LoadFrameImages(frame, ColourMode::kGrey); }),
              HasSubstr("big_depth.png"));
}

}  // namespace
}  // namespace moslam::io
