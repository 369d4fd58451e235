// Videos as sequences: frames decoded exactly (a lossless codec), stamps from the container or a
// rate, seeking back, and every bad file an InputError naming it.
#include "moslam/io/video.h"

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::io {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

// Frames of noise, so that any decoding difference shows.
std::vector<cv::Mat> Frames(int count) {
  std::vector<cv::Mat> frames;
  cv::RNG rng(7);
  for (int i = 0; i < count; ++i) {
    cv::Mat frame(48, 64, CV_8UC3);
    rng.fill(frame, cv::RNG::UNIFORM, 0, 256);
    frames.push_back(frame);
  }
  return frames;
}

// FFV1 in Matroska: lossless, in Debian's FFmpeg. Empty when this OpenCV cannot write it.
std::string WriteVideo(const std::string& path, const std::vector<cv::Mat>& frames, double fps) {
  cv::VideoWriter writer(path, cv::CAP_FFMPEG, cv::VideoWriter::fourcc('F', 'F', 'V', '1'), fps,
                         frames.front().size());
  if (!writer.isOpened()) return "";
  for (const cv::Mat& f : frames) writer.write(f);
  writer.release();
  return path;
}

TEST(Video, FramesAndContainerTimes) {
  const moslam::testing::TempDir dir;
  const std::vector<cv::Mat> frames = Frames(6);
  const std::string path = WriteVideo(dir.path() + "/clip.mkv", frames, 10.0);
  if (path.empty()) GTEST_SKIP() << "this OpenCV cannot write FFV1 video";
  const Sequence sequence = ReadVideo(path);
  ASSERT_EQ(sequence.size(), 6u);
  EXPECT_EQ(sequence.sensor, SensorType::kMonocular);
  EXPECT_EQ(sequence.name, "clip");
  for (int i = 0; i < 6; ++i) {
    EXPECT_NEAR(sequence.frames[i].timestamp, 0.1 * i, 1e-9);
    EXPECT_EQ(sequence.frames[i].index, i);
  }
  VideoReader reader(path);
  for (int i : {0, 1, 2, 4, 1, 5}) {  // forward, a skip, back
    const cv::Mat colour = reader.Read(i, ColourMode::kColour);
    EXPECT_EQ(cv::norm(colour, frames[i], cv::NORM_INF), 0.0) << "frame " << i;
  }
  cv::Mat grey;
  cv::cvtColor(frames[3], grey, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(reader.Read(3, ColourMode::kGrey), grey, cv::NORM_INF), 0.0);
  EXPECT_THAT(ErrorOf([&] { reader.Read(6, ColourMode::kGrey); }),
              HasSubstr("frame 6 cannot be decoded"));
}

TEST(Video, RateGivesTheStamps) {
  const moslam::testing::TempDir dir;
  const std::string path = WriteVideo(dir.path() + "/clip.mkv", Frames(3), 10.0);
  if (path.empty()) GTEST_SKIP() << "this OpenCV cannot write FFV1 video";
  VideoOptions options;
  options.rate_hz = 4.0;
  const Sequence sequence = ReadVideo(path, options);
  ASSERT_EQ(sequence.size(), 3u);
  EXPECT_EQ(sequence.frames[2].timestamp, 0.5);
  options.rate_hz = -1.0;
  EXPECT_THAT(ErrorOf([&] { ReadVideo(path, options); }), HasSubstr("positive number"));
}

TEST(Video, BadFilesNameThemselves) {
  const moslam::testing::TempDir dir;
  EXPECT_THAT(ErrorOf([&] { ReadVideo(dir.path() + "/none.mkv"); }),
              HasSubstr("none.mkv: no such video file"));
  EXPECT_THAT(ErrorOf([&] { ReadVideo(dir.path()); }), HasSubstr("is a folder"));
  const std::string text = dir.Write("notes.mp4", "this is not a video\n");
  const std::string error = ErrorOf([&] { ReadVideo(text); });
  EXPECT_THAT(error, HasSubstr("notes.mp4"));
  EXPECT_THAT(ErrorOf([&] { VideoReader reader(dir.path() + "/none.avi"); }),
              HasSubstr("none.avi"));
}

}  // namespace
}  // namespace moslam::io
