// Sensor models: what a Kinect-like RGB-D camera does to a perfect render.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

namespace moslam::synth {

struct DepthNoiseOptions {
  // Axial noise sigma(z) = sigma0 + k * (z - z0)^2 metres (Nguyen, Izadi & Lovell, 3DIMPVT 2012,
  // measured on the Kinect v1: 1.2 mm + 1.9 mm (z - 0.4 m)^2).
  double sigma0_m = 0.0012;
  double k_per_m = 0.0019;
  double z0_m = 0.4;
  // Disparity quantization: depth = bf / d with d in steps of 1/8 pixel (Kinect v1). bf in
  // pixel-metres (fx times the 7.5 cm projector baseline); 0 disables.
  double bf = 40.0;
  double disparity_step_px = 0.125;
  double min_range_m = 0.5;  // closer: no measurement (0)
  double max_range_m = 5.0;  // farther: no measurement
  // At depth edges (neighbour at least this much farther, relative), the farther pixel is lost
  // with probability edge_hole_probability (the projector's shadow).
  double edge_jump_ratio = 0.1;
  double edge_hole_probability = 0.6;
  double random_hole_probability = 0.002;
  bool enabled = true;  // false: exact depth (still quantized to the PNG's 1/5000 m)
};

struct ColourNoiseOptions {
  double sigma = 2.0;  // Gaussian noise per channel, 8-bit units
  bool enabled = true;
};

// Metric depth (CV_32F, 0 = nothing hit) -> TUM 16-bit depth (CV_16U, factor units per metre,
// 0 = hole) with the noise above. Deterministic in (seed, frame).
cv::Mat KinectDepth(const cv::Mat& depth_m, const DepthNoiseOptions& options, double factor,
                    uint64_t seed, uint64_t frame);

// Adds colour noise in place (CV_8UC3). Deterministic in (seed, frame).
void AddColourNoise(cv::Mat* rgb, const ColourNoiseOptions& options, uint64_t seed, uint64_t frame);

}  // namespace moslam::synth
