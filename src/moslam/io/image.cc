#include "moslam/io/image.h"

#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/util/error.h"

namespace moslam::io {
namespace {

cv::Mat Read(const std::string& path, int flags, const char* what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    ThrowInFile(path, fmt::format("{} not found (or not a regular file)", what));
  }
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    ThrowInFile(path, fmt::format("{} cannot be decoded: {}", what, e.err));
  }
  if (image.empty()) {
    ThrowInFile(path, fmt::format("{} cannot be read (unsupported or corrupt image file)", what));
  }
  return image;
}

void RequireSameSize(const cv::Mat& a, const std::string& a_path, const cv::Mat& b,
                     const std::string& b_path) {
  if (a.size() != b.size()) {
    ThrowInFile(b_path, fmt::format("image is {}x{} but '{}' of the same frame is {}x{}", b.cols,
                                    b.rows, a_path, a.cols, a.rows));
  }
}

}  // namespace

cv::Mat LoadGreyImage(const std::string& path) { return Read(path, cv::IMREAD_GRAYSCALE, "image"); }

cv::Mat LoadColourImage(const std::string& path) { return Read(path, cv::IMREAD_COLOR, "image"); }

cv::Mat LoadImage(const std::string& path, ColourMode mode) {
  return mode == ColourMode::kGrey ? LoadGreyImage(path) : LoadColourImage(path);
}

cv::Mat LoadDepthImage(const std::string& path, double depth_factor) {
  if (!std::isfinite(depth_factor) || !(depth_factor > 0.0)) {
    ThrowInput("depth factor must be a positive number of units per metre, got {}", depth_factor);
  }
  const cv::Mat raw = Read(path, cv::IMREAD_UNCHANGED, "depth image");
  if (raw.type() != CV_16UC1) {
    // An 8-bit or colour "depth" file is almost always the wrong file (e.g. an RGB image listed
    // in depth.txt); scaling it would silently produce nonsense depths.
    ThrowInFile(path, fmt::format("depth image must be 16-bit single-channel, got {} bit x {} "
                                  "channel(s)",
                                  raw.elemSize1() * 8, raw.channels()));
  }
  cv::Mat metres;
  raw.convertTo(metres, CV_32F, 1.0 / depth_factor);
  return metres;
}

FrameImages LoadFrameImages(const FrameEntry& frame, ColourMode mode, double depth_factor) {
  FrameImages images;
  images.left = LoadImage(frame.image_left, mode);
  // Stereo matching and depth lookup index both images with the same pixel coordinates.
  if (!frame.image_right.empty()) {
    images.right = LoadImage(frame.image_right, mode);
    RequireSameSize(images.left, frame.image_left, images.right, frame.image_right);
  }
  if (!frame.depth.empty()) {
    images.depth = LoadDepthImage(frame.depth, depth_factor);
    RequireSameSize(images.left, frame.image_left, images.depth, frame.depth);
  }
  return images;
}

}  // namespace moslam::io
