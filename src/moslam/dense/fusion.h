// A dense map of what stays: the depth of keyframes at their optimized poses fused into an
// occupancy octree (OctoMap, Hornung et al. 2013, Debian's liboctomap-dev), with the pixels of the
// movable-object mask left out, so that the people who walked through the view leave no trace
// (issue 27). Each depth pixel (on a grid of pixel_step) is a ray from the camera: the voxel at its
// end is observed occupied, those it passes free (OctoMap's insertPointCloud: the log-odds update
// of Moravec and Elfes), so a surface seen once and then seen through (a person who stood there
// and walked away) is cleared again by later rays. Masked pixels cast no ray at all: a person is
// neither added nor used to clear what is behind. Colours are averaged per voxel
// (ColorOcTree::integrateNodeColor).
//
// Not thread-safe; one instance per export.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "moslam/geometry/se3.h"

namespace octomap {
class ColorOcTree;
}  // namespace octomap

namespace moslam::dense {

// Pinhole intrinsics of the (undistorted, rectified) depth image.
struct Intrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;  // pixels (fx, fy > 0)
};

struct DenseFusionOptions {
  double resolution = 0.05;  // voxel edge, metres (> 0): 5 cm, as OctoMap's indoor examples
  int pixel_step = 4;        // one ray per pixel_step x pixel_step pixels (>= 1): 19,200 rays at
                             // 640x480, enough for 5 cm voxels up to ~4 m (a pixel spans 3 mm
                             // at 4 m, a 4-pixel step 3 cm)
  double min_depth = 0.1;    // metres (>= 0): nearer depths are sensor noise
  double max_depth = 4.0;    // metres (> min_depth): Kinect-type depth beyond ~4 m is too noisy
                             // for 5 cm voxels; KITTI stereo exports use ~30 m
  int mask_margin_px = 4;    // masked pixels grown by this much (>= 0): a body's outline has
                             // mixed depths of body and background
  bool ray_casting = true;   // clear the voxels along each ray (false: endpoints only)
  void Check() const;        // InputError naming the field
};

// One keyframe's input.
struct DepthView {
  geometry::SE3 T_world_cam;
  cv::Mat depth;   // CV_32FC1 metres, 0 or NaN = none
  cv::Mat colour;  // CV_8UC3 BGR of the depth's size, or empty (grey voxels)
  cv::Mat mask;    // CV_8UC1 of the depth's size, non-zero = movable; empty = none
};

struct InsertStats {
  size_t rays = 0;     // depth pixels inserted
  size_t masked = 0;   // grid pixels with a depth left out by the mask
  size_t invalid = 0;  // grid pixels without a usable depth
};

// An occupied voxel of the map: its centre and its averaged colour.
struct Voxel {
  Eigen::Vector3f centre;
  uint8_t r = 128, g = 128, b = 128;
};

class DenseFusion {
 public:
  DenseFusion(const Intrinsics& intrinsics, const DenseFusionOptions& options = {});
  ~DenseFusion();
  DenseFusion(const DenseFusion&) = delete;
  DenseFusion& operator=(const DenseFusion&) = delete;

  // Fuses one view. InputError when the images' types or sizes disagree.
  InsertStats Insert(const DepthView& view);
  // The occupied leaves (at the finest resolution), in a deterministic order.
  std::vector<Voxel> OccupiedVoxels() const;
  size_t NumOccupied() const;
  // OctoMap's compact binary format (.bt: occupancy only, readable by octovis and OcTree::
  // readBinary). InputError naming the file when it cannot be written.
  void WriteBinary(const std::string& path) const;
  const octomap::ColorOcTree& tree() const { return *tree_; }
  const DenseFusionOptions& options() const { return options_; }

 private:
  Intrinsics intrinsics_;
  DenseFusionOptions options_;
  std::unique_ptr<octomap::ColorOcTree> tree_;
};

// Which pixels of a view BackProject() keeps: those outside the mask grown by mask_margin_px
// (what the fusion inserts), or only those inside the mask as it is (the evaluation's
// ground-truth people).
enum class MaskUse { kLeaveOut, kOnly };

// The view's pixels (on the options' grid, within the depth range, chosen by `use`) back-projected
// into the world: what Insert() casts rays to. `colours` (may be null) gets their BGR colours,
// `stats` (may be null) the counts. InputError when the images' types or sizes disagree.
std::vector<Eigen::Vector3d> BackProject(const Intrinsics& intrinsics,
                                         const DenseFusionOptions& options, const DepthView& view,
                                         MaskUse use, std::vector<cv::Vec3b>* colours,
                                         InsertStats* stats);

}  // namespace moslam::dense
