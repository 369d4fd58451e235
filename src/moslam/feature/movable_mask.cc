// Mask geometry for movable objects (movable_mask.h).
#include "moslam/feature/movable_mask.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

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

// The written pixels' bounding box, grown as pixels are written.
struct Bounds {
  int u0 = std::numeric_limits<int>::max(), v0 = std::numeric_limits<int>::max();
  int u1 = -1, v1 = -1;  // inclusive
  cv::Rect rect() const { return u1 < 0 ? cv::Rect() : cv::Rect(u0, v0, u1 - u0 + 1, v1 - v0 + 1); }
};

// `z_out` (or null): the depth of what landed, the nearest kept; z 0 (no depth) never replaces.
void Splat(cv::Mat* out, double u, double v, uint8_t value, Bounds* bounds, cv::Mat* z_out,
           float z) {
  // The 2x2 pixels around (u, v): a surface seen up to twice as close leaves no cracks.
  const int u0 = static_cast<int>(std::floor(u)), v0 = static_cast<int>(std::floor(v));
  for (int y = v0; y <= v0 + 1; ++y) {
    if (y < 0 || y >= out->rows) continue;
    auto* row = out->ptr<uint8_t>(y);
    float* z_row = z_out != nullptr ? z_out->ptr<float>(y) : nullptr;
    for (int x = u0; x <= u0 + 1; ++x) {
      if (x < 0 || x >= out->cols) continue;
      if (row[x] == 0 || value < row[x]) row[x] = value;
      if (z_row != nullptr && z > 0.0f && (z_row[x] == 0.0f || z < z_row[x])) z_row[x] = z;
      bounds->u0 = std::min(bounds->u0, x), bounds->u1 = std::max(bounds->u1, x);
      bounds->v0 = std::min(bounds->v0, y), bounds->v1 = std::max(bounds->v1, y);
    }
  }
}

}  // namespace

cv::Mat WarpMask(const cv::Mat& values, const cv::Mat& depth, const camera::PinholeCamera& camera,
                 const geometry::SE3& T_to_from, const cv::Rect& source, cv::Rect* written,
                 cv::Mat* warped_depth) {
  MOSLAM_CHECK(values.type() == CV_8UC1);
  MOSLAM_CHECK(depth.empty() || (depth.type() == CV_32FC1 && depth.size() == values.size()));
  const cv::Rect area = source.empty() ? cv::Rect(0, 0, values.cols, values.rows)
                                       : source & cv::Rect(0, 0, values.cols, values.rows);
  cv::Mat out = cv::Mat::zeros(values.size(), CV_8UC1);
  if (warped_depth != nullptr) *warped_depth = cv::Mat::zeros(values.size(), CV_32FC1);
  Bounds bounds;
  const double fx = camera.fx(), fy = camera.fy(), cx = camera.cx(), cy = camera.cy();
  const Eigen::Matrix3d R = T_to_from.rotation().toRotationMatrix();
  const Eigen::Vector3d t = T_to_from.translation();
  std::vector<double> ray_x(values.cols);  // (u - cx) / fx once per column, not per pixel
  for (int u = area.x; u < area.x + area.width; ++u) ray_x[u] = (u - cx) / fx;
  for (int v = area.y; v < area.y + area.height; ++v) {
    const auto* src = values.ptr<uint8_t>(v);
    const float* d = depth.empty() ? nullptr : depth.ptr<float>(v);
    const double ray_y = (v - cy) / fy;
    for (int u = area.x; u < area.x + area.width; ++u) {
      if (src[u] == 0) continue;
      const Eigen::Vector3d ray(ray_x[u], ray_y, 1.0);
      const float z = d ? d[u] : 0.0f;
      // With depth: the point; without: the direction only (rotation, no translation).
      const bool with_depth = z > 0.0f && std::isfinite(z);
      const Eigen::Vector3d p =
          with_depth ? Eigen::Vector3d(R * (z * ray) + t) : Eigen::Vector3d(R * ray);
      if (p.z() <= 1e-6) continue;
      Splat(&out, fx * p.x() / p.z() + cx, fy * p.y() / p.z() + cy, src[u], &bounds, warped_depth,
            with_depth ? static_cast<float>(p.z()) : 0.0f);
    }
  }
  if (written != nullptr) *written = bounds.rect();
  return out;
}

cv::Mat DownsampleMask(const cv::Mat& mask, int factor) {
  MOSLAM_CHECK(factor >= 1 && mask.type() == CV_8UC1);
  if (factor == 1 || mask.empty()) return mask;
  const int w = (mask.cols + factor - 1) / factor, h = (mask.rows + factor - 1) / factor;
  cv::Mat small = cv::Mat::zeros(h, w, CV_8UC1);
  std::vector<uint8_t> any(mask.cols);  // the block row's columns, OR-ed over its rows
  for (int y = 0; y < h; ++y) {
    std::fill(any.begin(), any.end(), 0);
    for (int v = y * factor; v < std::min(mask.rows, (y + 1) * factor); ++v) {
      const auto* m = mask.ptr<uint8_t>(v);
      for (int u = 0; u < mask.cols; ++u) any[u] |= m[u];
    }
    auto* out = small.ptr<uint8_t>(y);
    if (factor == 2 && mask.cols % 2 == 0) {  // the common case, in a loop the compiler vectorizes
      for (int x = 0; x < w; ++x) out[x] = (any[2 * x] | any[2 * x + 1]) != 0 ? 255 : 0;
      continue;
    }
    for (int x = 0, u = 0; x < w; ++x) {
      uint8_t a = 0;
      for (const int end = std::min(mask.cols, u + factor); u < end; ++u) a |= any[u];
      out[x] = a != 0 ? 255 : 0;
    }
  }
  return small;
}

cv::Mat DownsampleDepth(const cv::Mat& depth, int factor) {
  MOSLAM_CHECK(factor >= 1 && depth.type() == CV_32FC1);
  if (factor == 1 || depth.empty()) return depth;
  const int w = (depth.cols + factor - 1) / factor, h = (depth.rows + factor - 1) / factor;
  cv::Mat small(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y) {
    const float* d = depth.ptr<float>(y * factor);
    auto* out = small.ptr<float>(y);
    for (int x = 0; x < w; ++x) out[x] = d[x * factor];
  }
  return small;
}

camera::PinholeCamera DownsampledCamera(const camera::PinholeCamera& camera, int factor) {
  MOSLAM_CHECK(factor >= 1);
  camera::PinholeOptions o;
  o.fx = camera.fx() / factor;
  o.fy = camera.fy() / factor;
  o.cx = camera.cx() / factor;
  o.cy = camera.cy() / factor;
  if (camera.width() > 0 && camera.height() > 0) {
    o.width = (camera.width() + factor - 1) / factor;
    o.height = (camera.height() + factor - 1) / factor;
  }
  return camera::PinholeCamera(o);
}

cv::Mat UpsampleMask(const cv::Mat& small, int factor, const cv::Size& size) {
  MOSLAM_CHECK(factor >= 1 && small.type() == CV_8UC1);
  MOSLAM_CHECK(small.cols == (size.width + factor - 1) / factor &&
               small.rows == (size.height + factor - 1) / factor);
  if (factor == 1) return small;
  cv::Mat out(size, CV_8UC1);
  for (int v = 0; v < size.height; ++v) {
    auto* o = out.ptr<uint8_t>(v);
    if (v % factor != 0) {  // the block's first row, again
      std::memcpy(o, out.ptr<uint8_t>(v - 1), static_cast<size_t>(size.width));
      continue;
    }
    const auto* s = small.ptr<uint8_t>(v / factor);
    if (factor == 2 && size.width % 2 == 0) {  // the common case, vectorized
      for (int u = 0; u < size.width; ++u) o[u] = s[u >> 1];
      continue;
    }
    for (int x = 0, u = 0; x < small.cols; ++x) {
      for (const int end = std::min(size.width, u + factor); u < end; ++u) o[u] = s[x];
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
  // Breadth-first, in a vector read from the front (the order of a FIFO queue without a
  // deque's block allocations: `perf` had the deque at 6 % of the completion).
  std::vector<Item> queue;
  queue.reserve(4096);
  const auto valid = [](float z) { return z > 0.0f && std::isfinite(z); };
  // Seeds: mask pixels with a valid depth next to a pixel outside the mask, looked for only in
  // the mask's bounding box.
  const cv::Rect box = cv::boundingRect(out);
  for (int v = box.y; v < box.y + box.height; ++v) {
    const auto* m = out.ptr<uint8_t>(v);
    const auto* up = v > 0 ? out.ptr<uint8_t>(v - 1) : nullptr;
    const auto* down = v + 1 < out.rows ? out.ptr<uint8_t>(v + 1) : nullptr;
    const float* d = depth.ptr<float>(v);
    for (int u = box.x; u < box.x + box.width; ++u) {
      if (m[u] == 0 || !valid(d[u])) continue;
      const bool border = (u > 0 && m[u - 1] == 0) || (u + 1 < out.cols && m[u + 1] == 0) ||
                          (up != nullptr && up[u] == 0) || (down != nullptr && down[u] == 0);
      if (border) queue.push_back({u, v, 0, d[u]});
    }
  }
  static const int kDu[4] = {1, -1, 0, 0}, kDv[4] = {0, 0, 1, -1};
  for (size_t head = 0; head < queue.size(); ++head) {
    const Item item = queue[head];
    if (item.steps >= options.max_grow_px) continue;
    const float z = depth.ptr<float>(item.v)[item.u];
    const double step = options.step_abs + options.step_rel * z;
    for (int k = 0; k < 4; ++k) {
      const int u = item.u + kDu[k], v = item.v + kDv[k];
      if (u < 0 || v < 0 || u >= out.cols || v >= out.rows) continue;
      uint8_t& m = out.ptr<uint8_t>(v)[u];
      if (m != 0) continue;
      const float zn = depth.ptr<float>(v)[u];
      if (!valid(zn)) continue;
      if (std::abs(zn - z) > step) continue;
      if (std::abs(zn - item.seed_depth) > options.max_depth_range) continue;
      if (structure != nullptr && structure->Contains(u, v, zn)) continue;
      m = 255;
      queue.push_back({u, v, item.steps + 1, item.seed_depth});
    }
  }
  return out;
}

}  // namespace moslam::feature
