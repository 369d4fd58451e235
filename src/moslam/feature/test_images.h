// Synthetic images for the feature tests and benchmark, so that they run without the shared data
// set: random grey blocks and discs over noise, lightly blurred, which gives FAST corners at
// every pyramid level; and movable-object masks made of rectangles and ellipses.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/camera/pinhole_camera.h"

namespace moslam::feature::test {

// An ideal 640x480 pinhole camera, f = 500 px, principal point at the centre.
inline camera::PinholeCamera TestCamera() {
  camera::PinholeOptions o;
  o.fx = o.fy = 500.0;
  o.cx = 320.0;
  o.cy = 240.0;
  o.width = 640;
  o.height = 480;
  return camera::PinholeCamera(o);
}

// A deterministic textured CV_8UC1 image.
inline cv::Mat TexturedImage(int width, int height, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(height, width, CV_8UC1);
  rng.fill(image, cv::RNG::UNIFORM, 60, 196);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 6.0);
  const int shapes = width * height / 300;
  for (int i = 0; i < shapes; ++i) {
    const int size = rng.uniform(3, 40);
    const cv::Point corner(rng.uniform(-size, width), rng.uniform(-size, height));
    const cv::Scalar grey(rng.uniform(0, 256));
    if (rng.uniform(0, 3) == 0) {
      cv::circle(image, corner, size / 2, grey, cv::FILLED, cv::LINE_8);
    } else {
      cv::rectangle(image, cv::Rect(corner, cv::Size(size, rng.uniform(3, 40))), grey, cv::FILLED);
    }
  }
  cv::GaussianBlur(image, image, cv::Size(0, 0), 0.8);
  return image;
}

// A mask (CV_8UC1, 255 = movable) of a few rectangles and ellipses, like cars and people,
// covering roughly `fraction` of the image.
inline cv::Mat MovableMask(cv::Size size, double fraction, uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat mask = cv::Mat::zeros(size, CV_8UC1);
  const double target = fraction * size.area();
  for (int i = 0; i < 100 && cv::countNonZero(mask) < target; ++i) {
    const int w = rng.uniform(size.width / 10, size.width / 4);
    const int h = rng.uniform(size.height / 8, size.height / 3);
    const cv::Point center(rng.uniform(0, size.width), rng.uniform(0, size.height));
    if (i % 2 == 0) {
      cv::rectangle(mask, cv::Rect(center.x - w / 2, center.y - h / 2, w, h), 255, cv::FILLED);
    } else {
      cv::ellipse(mask, center, cv::Size(w / 2, h / 2), 0, 0, 360, 255, cv::FILLED);
    }
  }
  return mask;
}

}  // namespace moslam::feature::test
