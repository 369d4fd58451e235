// Loading the images a FrameEntry lists. Every failure is an InputError naming the file: a
// missing file, one OpenCV cannot decode, or a depth image that is not 16-bit single-channel.
#pragma once

#include <string>

#include <opencv2/core.hpp>

#include "moslam/io/sequence.h"

namespace moslam::io {

// TUM RGB-D's depth scale: 5000 units per metre (a pixel value of 5000 is 1 m).
inline constexpr double kTumDepthFactor = 5000.0;

enum class ColourMode {
  kGrey,    // CV_8UC1 (colour files are converted by OpenCV's luminance formula)
  kColour,  // CV_8UC3 in OpenCV's BGR order (grey files are replicated into three channels)
};

// CV_8UC1.
cv::Mat LoadGreyImage(const std::string& path);
// CV_8UC3, BGR.
cv::Mat LoadColourImage(const std::string& path);
cv::Mat LoadImage(const std::string& path, ColourMode mode);

// A 16-bit single-channel depth image (TUM's PNGs) as CV_32FC1 metres: raw / depth_factor.
// 0 means "no measurement" and stays 0. depth_factor (raw units per metre) must be > 0.
cv::Mat LoadDepthImage(const std::string& path, double depth_factor = kTumDepthFactor);

struct FrameImages {
  cv::Mat left;   // always present
  cv::Mat right;  // stereo frames only; empty otherwise
  cv::Mat depth;  // RGB-D frames only (CV_32FC1 metres); empty otherwise
};

// Loads whatever images the frame lists.
FrameImages LoadFrameImages(const FrameEntry& frame, ColourMode mode,
                            double depth_factor = kTumDepthFactor);

}  // namespace moslam::io
