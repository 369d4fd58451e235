// Movable-object masks carried from frame to frame (issue 24; NGD-SLAM and CFP-SLAM propagate
// detections between network runs). A network that misses a body on one frame, or that runs
// only on every k-th frame (`moslam run --segment-every K`), leaves frames with no mask where a
// body still is: the last frame's mask, carried into the new frame with the camera's predicted
// motion and the depth under it, covers them. Carried pixels age by one per frame and fade after
// max_age frames; the network's pixels are age 1. The body's own motion is not modelled: the
// carried mask grows by grow_px per frame instead (a walking person moves ~10 px per frame at
// 30 frames/s and 2 m; depth completion, feature/movable_mask.h, refits it to the body).
//
// RGB-D: the exact warp with the depth under the mask (feature::WarpMask). Stereo and monocular
// have no dense depth here: the mask is carried by the rotation alone (right for far objects).
//
// RGB-D, the depth check: a carried pixel is dropped where the new frame's depth lies well
// behind the depth it was carried with. The warp moves a body's pixels as if the body stood
// still, so where it walked on, the carried pixels land on what was behind it (the table, the
// floor, the wall); kept, they were seeds from which the completion grew over those objects,
// and on w_rpy seed 29 with weak masks the frame's mask swelled from the network's 45-57 % to
// 72-79 % of the view, leaving 222 keypoints and losing tracking (docs/EVALUATION.md, "Carried
// masks that stay on the bodies"). Where the body still is, the depths agree and the pixel stays.
//
// One instance per tracking thread; not thread-safe.
#pragma once

#include <optional>

#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/se3.h"

namespace moslam::slam {

struct MaskPropagationOptions {
  int max_age = 3;  // frames a mask is carried after the network's last sight (>= 1)
  int grow_px = 2;  // the carried mask grows by this many pixels per frame (>= 0)
  // RGB-D: a carried pixel is dropped where the new depth is farther than the carried depth by
  // more than depth_gap_m + depth_gap_fraction x the carried depth (metres, >= 0; above).
  bool depth_check = true;
  double depth_gap_m = 0.15;
  double depth_gap_fraction = 0.05;
  void Check() const;  // InputError naming the field
};

class MaskPropagator {
 public:
  MaskPropagator(const camera::PinholeCamera& camera, const MaskPropagationOptions& options);

  // The mask of a new frame (CV_8UC1 0/255 of `size`): `network` (CV_8UC1 non-zero = movable,
  // or empty: none this frame) united with the last frame's mask carried by T_cur_last (the
  // motion from the last frame's camera into this one's; nullopt: unknown, carried unmoved).
  // `depth`: this frame's (CV_32FC1 metres of `size`, 0 = none) for the depth check, or empty.
  // Empty when no pixel is movable. Held until Commit().
  cv::Mat MaskFor(const cv::Mat& network, const cv::Size& size,
                  const std::optional<geometry::SE3>& T_cur_last, const cv::Mat& depth = cv::Mat());
  // Adds `region` (CV_8UC1 of the frame's size, non-zero = movable) to the mask of the frame
  // MaskFor was last called for, as the network's own pixels (age 1), so that it is carried into
  // the next frames: regions found after the frame was extracted (slam/moving_regions.h).
  void AddRegion(const cv::Mat& region);
  // The frame MaskFor was called for is done: its mask (with ages) and `depth` (CV_32FC1 metres
  // or empty) are what the next frame's mask is carried from.
  void Commit(const cv::Mat& depth);
  void Reset();

 private:
  // Ages one frame older, faded and grown, from `carried` into `ages` (views of one region).
  void CarryInto(const cv::Mat& carried, cv::Mat ages) const;
  // The depth check (above): clears the pixels of `carried` within `area` whose `depth` lies
  // behind their `carried_depth`.
  void DropWhereBehind(const cv::Mat& depth, const cv::Mat& carried_depth, const cv::Rect& area,
                       cv::Mat* carried) const;

  camera::PinholeCamera camera_;
  MaskPropagationOptions options_;
  cv::Mat last_ages_, last_depth_;  // last committed frame (empty: none)
  cv::Rect last_bounds_;            // where last_ages_ is non-zero (empty: nowhere)
  cv::Mat pending_ages_;            // the frame MaskFor was last called for
};

}  // namespace moslam::slam
