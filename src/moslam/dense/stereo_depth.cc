#include "moslam/dense/stereo_depth.h"

#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::dense {

void StereoDepthOptions::Check() const {
  if (num_disparities < 16 || num_disparities % 16 != 0) {
    throw InputError("StereoDepthOptions.num_disparities must be a positive multiple of 16, got " +
                     std::to_string(num_disparities));
  }
  if (block_size < 3 || block_size % 2 == 0) {
    throw InputError("StereoDepthOptions.block_size must be odd and >= 3, got " +
                     std::to_string(block_size));
  }
  if (uniqueness_ratio < 0 || uniqueness_ratio > 100) {
    throw InputError("StereoDepthOptions.uniqueness_ratio must be 0..100, got " +
                     std::to_string(uniqueness_ratio));
  }
}

namespace {
cv::Mat Grey(const cv::Mat& image) {
  if (image.channels() == 1) return image;
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  return grey;
}
}  // namespace

cv::Mat DepthFromStereo(const cv::Mat& left, const cv::Mat& right, double bf,
                        const StereoDepthOptions& options) {
  options.Check();
  if (left.empty() || left.size() != right.size() || left.depth() != CV_8U ||
      right.depth() != CV_8U) {
    throw InputError("stereo depth: the left and right images must be 8-bit and of one size");
  }
  if (!(bf > 0.0)) throw InputError("stereo depth: bf must be > 0, got " + std::to_string(bf));
  const int b = options.block_size;
  // P1, P2: the smoothness penalties OpenCV's documentation recommends for one channel.
  cv::Ptr<cv::StereoSGBM> sgbm =
      cv::StereoSGBM::create(0, options.num_disparities, b, 8 * b * b, 32 * b * b, 1, 63,
                             options.uniqueness_ratio, 100, 2, cv::StereoSGBM::MODE_SGBM);
  cv::Mat disparity16;
  sgbm->compute(Grey(left), Grey(right), disparity16);
  cv::Mat depth(left.size(), CV_32FC1, cv::Scalar(0.0f));
  for (int v = 0; v < depth.rows; ++v) {
    const int16_t* d = disparity16.ptr<int16_t>(v);
    float* z = depth.ptr<float>(v);
    // Fixed point with 4 fractional bits; below one pixel the depth is beyond any use.
    for (int u = 0; u < depth.cols; ++u) {
      if (d[u] >= 16) z[u] = static_cast<float>(bf * 16.0 / d[u]);
    }
  }
  return depth;
}

}  // namespace moslam::dense
