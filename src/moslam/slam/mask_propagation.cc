// Movable-object masks carried between frames (mask_propagation.h).
#include "moslam/slam/mask_propagation.h"

#include <opencv2/imgproc.hpp>

#include "moslam/feature/movable_mask.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void MaskPropagationOptions::Check() const {
  if (max_age < 1 || max_age > 250) {
    throw InputError("MaskPropagationOptions.max_age must be in 1..250 frames");
  }
  if (grow_px < 0) throw InputError("MaskPropagationOptions.grow_px must be >= 0");
  if (!(depth_gap_m >= 0.0) || !(depth_gap_fraction >= 0.0)) {
    throw InputError("MaskPropagationOptions.depth_gap_m and depth_gap_fraction must be >= 0");
  }
}

MaskPropagator::MaskPropagator(const camera::PinholeCamera& camera,
                               const MaskPropagationOptions& options)
    : camera_(camera), options_(options) {
  options_.Check();
}

cv::Mat MaskPropagator::MaskFor(const cv::Mat& network, const cv::Size& size,
                                const std::optional<geometry::SE3>& T_cur_last,
                                const cv::Mat& depth) {
  MOSLAM_CHECK(network.empty() || (network.type() == CV_8UC1 && network.size() == size));
  MOSLAM_CHECK(depth.empty() || (depth.type() == CV_32FC1 && depth.size() == size));
  cv::Mat ages = cv::Mat::zeros(size, CV_8UC1);
  if (!last_ages_.empty() && last_ages_.size() == size && !last_bounds_.empty()) {
    // Only the carried mask's bounding box (grown by the growth) is worked on: a body covers a
    // fifth of the view, and the fade, growth and copy of the whole image cost as much as the
    // warp itself.
    cv::Rect bounds = last_bounds_;
    const bool check = options_.depth_check && T_cur_last && !depth.empty() && !last_depth_.empty();
    cv::Mat carried_depth;
    cv::Mat carried =
        T_cur_last ? feature::WarpMask(last_ages_, last_depth_, camera_, *T_cur_last, last_bounds_,
                                       &bounds, check ? &carried_depth : nullptr)
                   : last_ages_;
    if (check) DropWhereBehind(depth, carried_depth, bounds, &carried);
    const cv::Rect roi = (bounds + cv::Point(-options_.grow_px, -options_.grow_px) +
                          cv::Size(2 * options_.grow_px, 2 * options_.grow_px)) &
                         cv::Rect(0, 0, size.width, size.height);
    if (!roi.empty()) CarryInto(carried(roi), ages(roi));
  }
  // The network's pixels (age 1), the mask and its pixel count in one pass.
  cv::Mat mask(size, CV_8UC1);
  int count = 0;
  for (int v = 0; v < size.height; ++v) {
    auto* a = ages.ptr<uint8_t>(v);
    auto* m = mask.ptr<uint8_t>(v);
    const auto* n = network.empty() ? nullptr : network.ptr<uint8_t>(v);
    for (int u = 0; u < size.width; ++u) {
      if (n != nullptr && n[u] != 0) a[u] = 1;
      m[u] = a[u] != 0 ? 255 : 0;
      count += a[u] != 0;
    }
  }
  pending_ages_ = ages;
  if (count == 0) return cv::Mat();  // nothing movable: as no mask
  return mask;
}

void MaskPropagator::CarryInto(const cv::Mat& carried, cv::Mat ages) const {
  // One frame older; the oldest fade. Stored inverted (255 - age) so that a dilation (a
  // maximum) grows the mask and keeps the youngest age where regions meet. `carried` is zero
  // beyond grow_px inside the region's edge, so the dilation of the region alone (outside the
  // image counts as nothing) equals that of the whole image.
  const cv::Size size = carried.size();
  cv::Mat inverted = cv::Mat::zeros(size, CV_8UC1);
  const int oldest = options_.max_age + 1;  // age 1 is the network's own frame
  for (int v = 0; v < size.height; ++v) {
    const auto* c = carried.ptr<uint8_t>(v);
    auto* out = inverted.ptr<uint8_t>(v);
    for (int u = 0; u < size.width; ++u) {
      if (c[u] != 0 && c[u] + 1 <= oldest) out[u] = static_cast<uint8_t>(255 - (c[u] + 1));
    }
  }
  if (options_.grow_px > 0) {
    const int k = 2 * options_.grow_px + 1;
    cv::dilate(inverted, inverted, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  }
  for (int v = 0; v < size.height; ++v) {
    const auto* in = inverted.ptr<uint8_t>(v);
    auto* a = ages.ptr<uint8_t>(v);
    for (int u = 0; u < size.width; ++u) {
      if (in[u] != 0) a[u] = static_cast<uint8_t>(255 - in[u]);
    }
  }
}

void MaskPropagator::DropWhereBehind(const cv::Mat& depth, const cv::Mat& carried_depth,
                                     const cv::Rect& area, cv::Mat* carried) const {
  const cv::Rect roi = area & cv::Rect(0, 0, depth.cols, depth.rows);
  const auto gap = static_cast<float>(options_.depth_gap_m);
  const auto fraction = static_cast<float>(1.0 + options_.depth_gap_fraction);
  for (int v = roi.y; v < roi.y + roi.height; ++v) {
    const float* now = depth.ptr<float>(v);
    const float* was = carried_depth.ptr<float>(v);
    auto* c = carried->ptr<uint8_t>(v);
    for (int u = roi.x; u < roi.x + roi.width; ++u) {
      // Both depths known, and the new one behind: the body has left this pixel. NaN compares
      // false, so an invalid depth keeps the pixel.
      if (c[u] != 0 && was[u] > 0.0f && now[u] > 0.0f && now[u] > fraction * was[u] + gap) c[u] = 0;
    }
  }
}

void MaskPropagator::AddRegion(const cv::Mat& region) {
  MOSLAM_CHECK(region.type() == CV_8UC1);
  if (pending_ages_.empty()) pending_ages_ = cv::Mat::zeros(region.size(), CV_8UC1);
  MOSLAM_CHECK(region.size() == pending_ages_.size());
  pending_ages_.setTo(1, region != 0);
}

void MaskPropagator::Commit(const cv::Mat& depth) {
  last_ages_ = pending_ages_;
  last_bounds_ = last_ages_.empty() ? cv::Rect() : cv::boundingRect(last_ages_);
  last_depth_ = depth;
  pending_ages_.release();
}

void MaskPropagator::Reset() {
  last_ages_.release();
  last_bounds_ = cv::Rect();
  last_depth_.release();
  pending_ages_.release();
}

}  // namespace moslam::slam
