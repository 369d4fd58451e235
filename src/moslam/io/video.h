// A video file as a monocular sequence (`moslam run --dataset video FILE`): any file OpenCV's
// VideoCapture opens (its FFmpeg backend: mp4, mkv, avi, ...). Frame k is stamped with the
// container's presentation time, or k / rate when a rate is given (a container without usable
// times, or to match another source's clock). Frames are decoded when tracking asks for them
// (VideoReader, in the loader thread): a video is never unpacked to disk.
#pragma once

#include <string>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

#include "moslam/io/image.h"
#include "moslam/io/sequence.h"

namespace moslam::io {

struct VideoOptions {
  double rate_hz = 0.0;  // > 0: frame k at k / rate_hz seconds; 0: the container's times
};

// Reads through the file once (containers do not always know their frame count) for the frames
// and their stamps. Every FrameEntry's image_left is the file; the frame is its index. InputError
// naming the file when it is missing, a folder, not a video OpenCV can decode, has no frames, or
// (without a rate) has stamps that do not increase.
Sequence ReadVideo(const std::string& path, const VideoOptions& options = {});

// Decodes frames in order; a frame before the last one read is reached by seeking.
class VideoReader {
 public:
  explicit VideoReader(const std::string& path);  // InputError when it cannot be opened
  // Frame `index` (0-based) as ColourMode says; InputError naming the file and the frame when it
  // cannot be decoded.
  cv::Mat Read(int index, ColourMode mode);

 private:
  std::string path_;
  cv::VideoCapture capture_;
  int next_ = 0;  // the index of the frame the next read() returns
};

}  // namespace moslam::io
