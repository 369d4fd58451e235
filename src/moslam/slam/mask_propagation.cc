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
}

MaskPropagator::MaskPropagator(const camera::PinholeCamera& camera,
                               const MaskPropagationOptions& options)
    : camera_(camera), options_(options) {
  options_.Check();
}

cv::Mat MaskPropagator::MaskFor(const cv::Mat& network, const cv::Size& size,
                                const std::optional<geometry::SE3>& T_cur_last) {
  MOSLAM_CHECK(network.empty() || (network.type() == CV_8UC1 && network.size() == size));
  cv::Mat ages = cv::Mat::zeros(size, CV_8UC1);
  if (!last_ages_.empty() && last_ages_.size() == size) {
    const cv::Mat carried =
        T_cur_last ? feature::WarpMask(last_ages_, last_depth_, camera_, *T_cur_last) : last_ages_;
    // One frame older; the oldest fade. Stored inverted (255 - age) so that a dilation (a
    // maximum) grows the mask and keeps the youngest age where regions meet.
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
  if (!network.empty()) ages.setTo(1, network != 0);
  pending_ages_ = ages;
  if (cv::countNonZero(ages) == 0) return cv::Mat();  // nothing movable: as no mask
  cv::Mat mask;
  cv::threshold(ages, mask, 0, 255, cv::THRESH_BINARY);
  return mask;
}

void MaskPropagator::AddRegion(const cv::Mat& region) {
  MOSLAM_CHECK(region.type() == CV_8UC1);
  if (pending_ages_.empty()) pending_ages_ = cv::Mat::zeros(region.size(), CV_8UC1);
  MOSLAM_CHECK(region.size() == pending_ages_.size());
  pending_ages_.setTo(1, region != 0);
}

void MaskPropagator::Commit(const cv::Mat& depth) {
  last_ages_ = pending_ages_;
  last_depth_ = depth;
  pending_ages_.release();
}

void MaskPropagator::Reset() {
  last_ages_.release();
  last_depth_.release();
  pending_ages_.release();
}

}  // namespace moslam::slam
