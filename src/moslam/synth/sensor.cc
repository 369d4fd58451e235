#include "moslam/synth/sensor.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "moslam/synth/rng.h"
#include "moslam/util/check.h"

namespace moslam::synth {
namespace {
constexpr uint64_t kStreamDepth = 0xDE9, kStreamColour = 0xC010;
}  // namespace

cv::Mat KinectDepth(const cv::Mat& depth_m, const DepthNoiseOptions& o, double factor,
                    uint64_t seed, uint64_t frame) {
  MOSLAM_CHECK(depth_m.type() == CV_32FC1);
  cv::Mat out(depth_m.size(), CV_16UC1, cv::Scalar(0));
  Rng rng(seed ^ (frame * 0x9E3779B97F4A7C15ULL), kStreamDepth);
  // Standard normal samples drawn by Box-Muller into a table, indexed by 16 random bits per
  // pixel: a Box-Muller per pixel costs more than the rendering.
  std::vector<float> normal(65536);
  for (float& v : normal) v = static_cast<float>(rng.Normal());
  const int w = depth_m.cols, h = depth_m.rows;
  for (int y = 0; y < h; ++y) {
    const float* row = depth_m.ptr<float>(y);
    uint16_t* dst = out.ptr<uint16_t>(y);
    for (int x = 0; x < w; ++x) {
      double z = row[x];
      if (!o.enabled) {
        if (z > 0) dst[x] = static_cast<uint16_t>(std::min(65535.0, std::round(z * factor)));
        continue;
      }
      // One 64-bit draw per pixel whatever happens, so that a hole in one place does not shift
      // the noise of every later pixel.
      const uint64_t r = rng.Next();
      const double n = normal[r & 0xFFFF];
      const double u_edge = static_cast<double>((r >> 16) & 0xFFFF) / 65536.0;
      const double u_hole = static_cast<double>(r >> 32) * 0x1.0p-32;
      if (z <= 0 || z < o.min_range_m || z > o.max_range_m || u_hole < o.random_hole_probability) {
        continue;
      }
      bool edge = false;
      const int nx[4] = {-1, 1, 0, 0}, ny[4] = {0, 0, -1, 1};
      for (int k = 0; k < 4 && !edge; ++k) {
        const int xx = x + nx[k], yy = y + ny[k];
        if (xx < 0 || yy < 0 || xx >= w || yy >= h) continue;
        const double zn = depth_m.at<float>(yy, xx);
        edge = zn > 0 && z > zn * (1.0 + o.edge_jump_ratio);
      }
      if (edge && u_edge < o.edge_hole_probability) continue;
      const double sigma = o.sigma0_m + o.k_per_m * (z - o.z0_m) * (z - o.z0_m);
      z += sigma * n;
      if (o.bf > 0 && o.disparity_step_px > 0) {
        const double d = std::round(o.bf / z / o.disparity_step_px) * o.disparity_step_px;
        if (d <= 0) continue;
        z = o.bf / d;
      }
      dst[x] = static_cast<uint16_t>(std::clamp(std::round(z * factor), 0.0, 65535.0));
    }
  }
  return out;
}

void AddColourNoise(cv::Mat* rgb, const ColourNoiseOptions& o, uint64_t seed, uint64_t frame) {
  if (!o.enabled || o.sigma <= 0) return;
  MOSLAM_CHECK(rgb->type() == CV_8UC3 && rgb->isContinuous());
  Rng rng(seed ^ (frame * 0x9E3779B97F4A7C15ULL), kStreamColour);
  // A table of 4096 Gaussian samples indexed by the generator: Box-Muller for every channel of
  // every pixel would cost more than the rendering.
  float table[4096];
  for (float& v : table) v = static_cast<float>(o.sigma * rng.Normal());
  uint8_t* p = rgb->data;
  const size_t n = rgb->total() * 3;
  for (size_t i = 0; i < n; i += 4) {
    const uint64_t r = rng.Next();
    for (size_t k = 0; k < 4 && i + k < n; ++k) {
      const float v = p[i + k] + table[(r >> (16 * k)) & 4095];
      p[i + k] = static_cast<uint8_t>(std::clamp(std::lround(v), 0L, 255L));
    }
  }
}

}  // namespace moslam::synth
