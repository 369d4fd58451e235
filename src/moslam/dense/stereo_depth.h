// Dense depth of a rectified stereo pair for the dense map: OpenCV's semi-global block matching
// (Hirschmüller 2008, cv::StereoSGBM), depth = bf / disparity. Tracking keeps its own sparse,
// sub-pixel stereo matches (feature/stereo_matcher.h); this is only for fusion, where a dense
// surface matters more than the last tenth of a pixel.
#pragma once

#include <opencv2/core.hpp>

namespace moslam::dense {

struct StereoDepthOptions {
  int num_disparities = 128;  // search range, pixels (a positive multiple of 16): KITTI's
                              // bf = 387 px m reaches down to 3 m
  int block_size = 5;         // odd, >= 3
  int uniqueness_ratio = 10;  // percent margin of the best match over the second
  void Check() const;         // InputError naming the field
};

// CV_32FC1 metres, 0 where no disparity was found. left/right: CV_8UC1 (or colour, converted) of
// the same size; bf: baseline times fx (pixel-metres, > 0). InputError otherwise.
cv::Mat DepthFromStereo(const cv::Mat& left, const cv::Mat& right, double bf,
                        const StereoDepthOptions& options = {});

}  // namespace moslam::dense
