// The movable mask a frame is extracted with (issue 24): the network's (or any source's) mask
// united with the masks carried from the last frames (mask_propagation.h) and, with depth, grown
// over the depth-connected surface it covers, kept off the frame's large planes
// (feature::CompleteMaskByDepth, feature::StructurePlanes).
//
// The carrying and the growth run at a coarser scale (`work_scale`, 2 by default: 320x240 for
// a 640x480 camera) and the result is brought back to the image's size. Their cost is in
// proportion to the pixels they touch (at full size they took 3.5 ms of a frame on this 2-core
// machine, against the budget of 3 ms for every mechanism together), and a mask for the
// extractor needs no pixel accuracy: ORB keypoints describe a 31 px patch, and new map points
// keep a 4 px margin from a mask anyway. The network's own pixels are always in the result
// (its mask is pooled with "any", so every pixel of a masked block stays masked).
//
// One instance per tracking thread; not thread-safe.
#pragma once

#include <memory>
#include <optional>

#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/se3.h"
#include "moslam/slam/mask_propagation.h"

namespace moslam::slam {

struct FrameMaskOptions {
  // Frames a mask is carried after its last sight (0: no carrying; MaskPropagationOptions).
  int propagation_frames = 3;
  // RGB-D: carried pixels are dropped where the new depth shows the body has left them
  // (MaskPropagationOptions::depth_check).
  bool propagation_depth_check = true;
  // Farthest a mask grows over depth-connected pixels, in full-size pixels (0: no growth).
  int completion_px = 400;
  // Whether the growth stays off the frame's large planes.
  bool completion_structure = true;
  // The carrying and the growth run on images downsampled by this factor (1..4; 1: full size).
  int work_scale = 2;
  void Check() const;  // InputError naming the field
};

class FrameMask {
 public:
  FrameMask(const camera::PinholeCamera& camera, const FrameMaskOptions& options);

  // The mask of a new frame (CV_8UC1 0/255 of the image's `size`, or empty when nothing is
  // movable): `network` (CV_8UC1 of `size`, non-zero = movable, or empty) with the carried and
  // grown pixels. `depth` is the frame's (CV_32FC1 metres) or empty; T_cur_last the motion from
  // the last frame's camera into this one's (nullopt: unknown). Held until Commit().
  cv::Mat MaskFor(const cv::Mat& network, const cv::Mat& depth, const cv::Size& size,
                  const std::optional<geometry::SE3>& T_cur_last);
  // Adds `region` (CV_8UC1 of the image's size) to the frame's carried mask as if the network
  // had marked it (slam/moving_regions.h). No effect without carrying.
  void AddRegion(const cv::Mat& region);
  // The frame MaskFor was last called for is done: it is what the next frame's mask is carried
  // from.
  void Commit();
  bool carries() const { return propagator_ != nullptr; }

 private:
  FrameMaskOptions options_;
  camera::PinholeCamera work_camera_;           // the camera of the downsampled images
  std::unique_ptr<MaskPropagator> propagator_;  // null without carrying
  cv::Mat work_depth_;                          // the last MaskFor's depth, downsampled
};

}  // namespace moslam::slam
