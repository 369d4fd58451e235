// Small synthetic inputs shared by the CRF tests.
#pragma once

#include <cstdint>
#include <random>

#include <opencv2/core.hpp>

namespace moslam::semantic::testing {

inline cv::Mat Planar(int labels, int rows, int cols) {
  const int sizes[3] = {labels, rows, cols};
  return cv::Mat(3, sizes, CV_32F, cv::Scalar(0));
}

// Random smooth-ish probabilities, normalized per pixel.
inline cv::Mat RandomProbabilities(int labels, int rows, int cols, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(0.05f, 1.0f);
  cv::Mat probs = Planar(labels, rows, cols);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      float sum = 0.0f;
      for (int l = 0; l < labels; ++l) sum += (probs.at<float>(l, y, x) = uniform(rng));
      for (int l = 0; l < labels; ++l) probs.at<float>(l, y, x) /= sum;
    }
  }
  return probs;
}

// Two colour regions split by a slanted edge, with noise.
inline cv::Mat TwoRegionImage(int rows, int cols, uint32_t seed) {
  cv::Mat image(rows, cols, CV_8UC3);
  std::mt19937 rng(seed);
  std::normal_distribution<float> noise(0.0f, 6.0f);
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) {
      const bool right = x > cols / 2 + (y - rows / 2) / 3;
      const cv::Vec3f base = right ? cv::Vec3f(40, 160, 200) : cv::Vec3f(180, 60, 50);
      for (int c = 0; c < 3; ++c) {
        image.at<cv::Vec3b>(y, x)[c] = cv::saturate_cast<uint8_t>(base[c] + noise(rng));
      }
    }
  }
  return image;
}

}  // namespace moslam::semantic::testing
