// Mask geometry for movable objects (movable_mask.h).
#include "moslam/feature/movable_mask.h"

#include <cmath>
#include <deque>
#include <string>

#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::feature {

std::vector<uint8_t> KeypointsNearMask(const std::vector<cv::KeyPoint>& keypoints,
                                       const cv::Mat& mask, int margin_px) {
  std::vector<uint8_t> near(keypoints.size(), 0);
  if (mask.empty() || margin_px < 0) return near;
  MOSLAM_CHECK(mask.type() == CV_8UC1);
  cv::Mat grown;  // never a header of `mask`: dilate would write into the caller's image
  if (margin_px > 0) {
    const int k = 2 * margin_px + 1;
    cv::dilate(mask, grown, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)));
  } else {
    grown = mask;
  }
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const int u = static_cast<int>(std::lround(keypoints[i].pt.x));
    const int v = static_cast<int>(std::lround(keypoints[i].pt.y));
    if (u >= 0 && v >= 0 && u < grown.cols && v < grown.rows && grown.at<uint8_t>(v, u) != 0) {
      near[i] = 1;
    }
  }
  return near;
}

namespace {

void Splat(cv::Mat* out, double u, double v, uint8_t value) {
  // The 2x2 pixels around (u, v): a surface seen up to twice as close leaves no cracks.
  const int u0 = static_cast<int>(std::floor(u)), v0 = static_cast<int>(std::floor(v));
  for (int y = v0; y <= v0 + 1; ++y) {
    if (y < 0 || y >= out->rows) continue;
    auto* row = out->ptr<uint8_t>(y);
    for (int x = u0; x <= u0 + 1; ++x) {
      if (x < 0 || x >= out->cols) continue;
      if (row[x] == 0 || value < row[x]) row[x] = value;
    }
  }
}

}  // namespace

cv::Mat WarpMask(const cv::Mat& values, const cv::Mat& depth, const camera::PinholeCamera& camera,
                 const geometry::SE3& T_to_from) {
  MOSLAM_CHECK(values.type() == CV_8UC1);
  MOSLAM_CHECK(depth.empty() || (depth.type() == CV_32FC1 && depth.size() == values.size()));
  cv::Mat out = cv::Mat::zeros(values.size(), CV_8UC1);
  const double fx = camera.fx(), fy = camera.fy(), cx = camera.cx(), cy = camera.cy();
  const Eigen::Matrix3d R = T_to_from.rotation().toRotationMatrix();
  const Eigen::Vector3d t = T_to_from.translation();
  for (int v = 0; v < values.rows; ++v) {
    const auto* src = values.ptr<uint8_t>(v);
    const float* d = depth.empty() ? nullptr : depth.ptr<float>(v);
    for (int u = 0; u < values.cols; ++u) {
      if (src[u] == 0) continue;
      const Eigen::Vector3d ray((u - cx) / fx, (v - cy) / fy, 1.0);
      const float z = d ? d[u] : 0.0f;
      // With depth: the point; without: the direction only (rotation, no translation).
      const Eigen::Vector3d p = (z > 0.0f && std::isfinite(z)) ? Eigen::Vector3d(R * (z * ray) + t)
                                                               : Eigen::Vector3d(R * ray);
      if (p.z() <= 1e-6) continue;
      Splat(&out, fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy, src[u]);
    }
  }
  return out;
}

void MaskCompletionOptions::Check() const {
  if (max_grow_px < 0) throw InputError("MaskCompletionOptions.max_grow_px must be >= 0");
  if (!(step_abs >= 0.0) || !(step_rel >= 0.0)) {
    throw InputError("MaskCompletionOptions.step_abs and step_rel must be >= 0");
  }
  if (!(max_depth_range > 0.0)) {
    throw InputError("MaskCompletionOptions.max_depth_range must be > 0");
  }
}

cv::Mat CompleteMaskByDepth(const cv::Mat& mask, const cv::Mat& depth,
                            const MaskCompletionOptions& options,
                            const StructurePlanes* structure) {
  options.Check();
  MOSLAM_CHECK(mask.type() == CV_8UC1);
  MOSLAM_CHECK(depth.type() == CV_32FC1 && depth.size() == mask.size());
  cv::Mat out;
  cv::threshold(mask, out, 0, 255, cv::THRESH_BINARY);
  if (options.max_grow_px == 0) return out;
  struct Item {
    int u, v, steps;
    float seed_depth;
  };
  // Seeds: mask pixels with a valid depth next to a pixel outside the mask.
  std::deque<Item> queue;
  const auto valid = [](float z) { return z > 0.0f && std::isfinite(z); };
  for (int v = 0; v < out.rows; ++v) {
    const auto* m = out.ptr<uint8_t>(v);
    const float* d = depth.ptr<float>(v);
    for (int u = 0; u < out.cols; ++u) {
      if (m[u] == 0 || !valid(d[u])) continue;
      const bool border = (u > 0 && m[u - 1] == 0) || (u + 1 < out.cols && m[u + 1] == 0) ||
                          (v > 0 && out.at<uint8_t>(v - 1, u) == 0) ||
                          (v + 1 < out.rows && out.at<uint8_t>(v + 1, u) == 0);
      if (border) queue.push_back({u, v, 0, d[u]});
    }
  }
  static const int kDu[4] = {1, -1, 0, 0}, kDv[4] = {0, 0, 1, -1};
  while (!queue.empty()) {
    const Item item = queue.front();
    queue.pop_front();
    if (item.steps >= options.max_grow_px) continue;
    const float z = depth.at<float>(item.v, item.u);
    for (int k = 0; k < 4; ++k) {
      const int u = item.u + kDu[k], v = item.v + kDv[k];
      if (u < 0 || v < 0 || u >= out.cols || v >= out.rows) continue;
      uint8_t& m = out.at<uint8_t>(v, u);
      if (m != 0) continue;
      const float zn = depth.at<float>(v, u);
      if (!valid(zn)) continue;
      if (std::abs(zn - z) > options.step_abs + options.step_rel * z) continue;
      if (std::abs(zn - item.seed_depth) > options.max_depth_range) continue;
      if (structure != nullptr && structure->Contains(u, v, zn)) continue;
      m = 255;
      queue.push_back({u, v, item.steps + 1, item.seed_depth});
    }
  }
  return out;
}

}  // namespace moslam::feature
