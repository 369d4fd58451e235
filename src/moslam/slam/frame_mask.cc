// The movable mask a frame is extracted with (frame_mask.h).
#include "moslam/slam/frame_mask.h"

#include <cmath>

#include "moslam/feature/movable_mask.h"
#include "moslam/feature/structure_planes.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void FrameMaskOptions::Check() const {
  if (propagation_frames < 0 || propagation_frames > 250) {
    throw InputError("FrameMaskOptions.propagation_frames must be in 0..250");
  }
  if (completion_px < 0) throw InputError("FrameMaskOptions.completion_px must be >= 0");
  if (work_scale < 1 || work_scale > 4) {
    throw InputError("FrameMaskOptions.work_scale must be in 1..4");
  }
}

FrameMask::FrameMask(const camera::PinholeCamera& camera, const FrameMaskOptions& options)
    : options_(options),
      work_camera_(feature::DownsampledCamera(camera, std::max(1, options.work_scale))) {
  options_.Check();
  if (options_.propagation_frames > 0) {
    MaskPropagationOptions propagation;
    propagation.max_age = options_.propagation_frames;
    // The growth per frame stays the same in the image (2 px: 1 work pixel at scale 2).
    const int s = options_.work_scale;
    propagation.grow_px = (propagation.grow_px + s - 1) / s;
    propagation.depth_check = options_.propagation_depth_check;
    propagator_ = std::make_unique<MaskPropagator>(work_camera_, propagation);
  }
}

cv::Mat FrameMask::MaskFor(const cv::Mat& network, const cv::Mat& depth, const cv::Size& size,
                           const std::optional<geometry::SE3>& T_cur_last) {
  MOSLAM_CHECK(network.empty() || (network.type() == CV_8UC1 && network.size() == size));
  MOSLAM_CHECK(depth.empty() || (depth.type() == CV_32FC1 && depth.size() == size));
  const int s = options_.work_scale;
  const bool grow = options_.completion_px > 0 && !depth.empty();
  if (!propagator_ && !grow) return network;
  work_depth_ = depth.empty() ? cv::Mat() : feature::DownsampleDepth(depth, s);
  const cv::Size work_size((size.width + s - 1) / s, (size.height + s - 1) / s);
  cv::Mat mask = network.empty() ? cv::Mat() : feature::DownsampleMask(network, s);
  if (propagator_) mask = propagator_->MaskFor(mask, work_size, T_cur_last, work_depth_);
  if (grow && !mask.empty() && cv::countNonZero(mask) > 0) {
    feature::MaskCompletionOptions completion;
    completion.max_grow_px = (options_.completion_px + s - 1) / s;
    std::optional<feature::StructurePlanes> structure;
    if (options_.completion_structure) {
      // The grid keeps its step in work pixels: at scale 2, 1200 samples (16 px apart in the
      // full image) find the floor and the walls as well, at a quarter of the cost.
      const feature::StructurePlaneOptions planes;
      structure = feature::StructurePlanes::Find(work_depth_, work_camera_, mask, planes);
    }
    mask = feature::CompleteMaskByDepth(mask, work_depth_, completion,
                                        structure ? &*structure : nullptr);
  }
  if (mask.empty()) return mask;
  return feature::UpsampleMask(mask, s, size);
}

void FrameMask::AddRegion(const cv::Mat& region) {
  if (!propagator_) return;
  propagator_->AddRegion(feature::DownsampleMask(region, options_.work_scale));
}

void FrameMask::Commit() {
  if (propagator_) propagator_->Commit(work_depth_);
}

}  // namespace moslam::slam
