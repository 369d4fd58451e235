// Image-space operations on movable-object masks that need geometry (issue 24): which keypoints
// lie near a mask (no new map point is made there: a mask's border is where a weak network is
// least sure of a body's extent), a mask carried into another view with the depth under it
// (temporal propagation, as NGD-SLAM and CFP-SLAM propagate detections between network runs), and
// a mask grown over the depth-connected surface it covers (depth-guided completion, CFP-SLAM's
// depth clustering in a bounded, local form).
//
// Masks are CV_8UC1 of the image's size; non-zero = movable. Depth images are CV_32FC1 metres,
// registered to the mask (0 or non-finite = invalid), as slam::FrameInput::depth.
#pragma once

#include <cstdint>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/feature/structure_planes.h"
#include "moslam/geometry/se3.h"

namespace moslam::feature {

// Per keypoint (raw image coordinates): 1 when a non-zero mask pixel lies within margin_px
// (Chebyshev distance) of it, else 0. Empty mask or margin_px < 0: all 0.
std::vector<uint8_t> KeypointsNearMask(const std::vector<cv::KeyPoint>& keypoints,
                                       const cv::Mat& mask, int margin_px);

// Forward warp of a mask into a second view. `values` is CV_8UC1 (0 = not movable; any other
// value is carried as is, e.g. an age); every non-zero pixel with a valid depth is lifted with
// `depth`, moved by T_to_from (from the mask's camera into the target camera) and splatted on the
// 2x2 pixels around its projection (so a mask seen closer leaves no cracks); where several land
// on one pixel the smallest value wins. Pixels without depth are carried by the rotation alone
// (a point at infinity). Distortion is ignored: ideal pinhole pixels (the synthetic and
// rectified cameras this is used with have none; TUM's small distortion moves a pixel by < 2 px).
// With an empty `depth`, every pixel is carried by the rotation (the infinite homography
// K R K^-1): right for far objects, and all a camera without dense depth can do.
// `source`, when not empty, is where `values` may be non-zero (the caller knows it, e.g. from
// the last frame): only it is read. `written`, when given, receives the bounding box of the
// pixels the warp wrote (empty when none), so that the caller can work on that part alone.
// `warped_depth`, when given, receives (CV_32FC1) the depth in the target camera of the point
// that landed on each written pixel (the nearest where several did; 0 where none, or where the
// pixel came without depth): where the target's own depth is farther, what was carried has left.
cv::Mat WarpMask(const cv::Mat& values, const cv::Mat& depth, const camera::PinholeCamera& camera,
                 const geometry::SE3& T_to_from, const cv::Rect& source = cv::Rect(),
                 cv::Rect* written = nullptr, cv::Mat* warped_depth = nullptr);

// The mask work at a coarser scale (SystemOptions::mask_work_scale): propagation, structure
// planes and completion cost in proportion to the pixels they touch, and a mask carried or grown
// at half resolution is as good for keeping keypoints off a body (ORB keypoints need a 31 px
// patch; masks keep a 4 px margin) at a quarter of the cost. `factor` >= 1; 1 returns the input.
//
// The mask with one pixel per factor x factor block, non-zero (255) where any pixel of the block
// is non-zero: a body's thin parts are never lost.
cv::Mat DownsampleMask(const cv::Mat& mask, int factor);
// The depth (CV_32FC1) at every factor-th pixel of every factor-th row (no averaging across a
// body's edge, which would make depths that lie on neither side).
cv::Mat DownsampleDepth(const cv::Mat& depth, int factor);
// The ideal pinhole camera of images downsampled that way: pixel (x, y) of the small image is
// pixel (factor x, factor y) of the full one.
camera::PinholeCamera DownsampledCamera(const camera::PinholeCamera& camera, int factor);
// A mask downsampled by `factor` brought back to `size` (each pixel repeated factor x factor
// times; `small` must have the size DownsampleMask gives for `size`).
cv::Mat UpsampleMask(const cv::Mat& small, int factor, const cv::Size& size);

struct MaskCompletionOptions {
  // Farthest a mask grows from where it was, in pixels (4-connected steps); 0 = off. Far enough
  // to cover a body from its head (a person 1 m away is ~500 px tall); what keeps the growth off
  // the floor the feet touch is the structure planes (CompleteMaskByDepth's `structure`), and
  // without them this bound alone (12 px before 2026-12-03).
  int max_grow_px = 400;
  // A neighbour joins when its depth differs from the pixel it is reached from by at most
  // step_abs + step_rel * depth (metres): a depth edge (a body in front of a wall) stops it.
  double step_abs = 0.02;
  double step_rel = 0.01;
  // ... and from the depth of the mask pixel the growth started at by at most this (metres):
  // a slanted floor or wall, connected step by step, does not run far.
  double max_depth_range = 0.3;
  void Check() const;  // InputError naming the field
};

// The mask (CV_8UC1, 0/255) grown over depth-connected pixels: breadth-first from the mask's
// pixels with a valid depth, through 4-neighbours that pass both depth tests, up to max_grow_px
// steps. The input's pixels are all kept. With `structure`, no pixel on one of its planes is
// entered: a body is completed from its head or legs over the whole depth-connected surface
// while the floor it stands on, depth-connected through the feet, stays out (structure_planes.h).
cv::Mat CompleteMaskByDepth(const cv::Mat& mask, const cv::Mat& depth,
                            const MaskCompletionOptions& options,
                            const StructurePlanes* structure = nullptr);

}  // namespace moslam::feature
