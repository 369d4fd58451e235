// The large planes of a depth image (floor, walls, ceiling, long table tops): what a movable
// object stands on or in front of, and what a mask grown over depth-connected surfaces must not
// enter (feature::CompleteMaskByDepth, issue 24). A walking person touches the floor with the
// feet, so the floor is depth-connected to the body; without this, a mask grown from the legs
// runs along the floor as far as its depth range allows (measured on w_rpy seed 22 with exact
// masks: 27 000 wrongly masked pixels a frame, 0.0039 -> 0.0075 m ATE).
//
// Sequential RANSAC (Fischler and Bolles 1981) on a regular grid of depth samples, as in
// plane-based RGB-D segmentation (e.g. Holz et al. 2011, Trevor et al. 2013's organised
// segmentation): the plane with the most inliers among the remaining samples, then its largest
// 4-connected part on the grid; that part is kept as structure when it is large in metres (its
// second principal extent >= min_side_m), so a person's flat torso (0.4-0.6 m across), a box face
// or a chair seat is never structure, while a desk top (0.8 m deep) is. Deterministic (fixed
// seed).
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"

namespace moslam::feature {

struct StructurePlaneOptions {
  // Sampling step of the depth grid, pixels (8: 4800 samples at 640x480).
  int grid_px = 8;
  // Most planes tried (each removes its part's samples before the next), at most 8.
  int max_planes = 6;
  // RANSAC hypotheses per plane ...
  int iterations = 150;
  // ... each scored on every score_stride-th sample (1: all; 4 cuts the cost by ~3.5x).
  int score_stride = 4;
  // A sample is on a plane within inlier_abs + inlier_rel * depth metres (depth noise grows
  // with depth).
  double inlier_abs = 0.02;
  double inlier_rel = 0.01;
  // A part counts only with at least this share of the valid samples ...
  double min_share = 0.03;
  // ... and a second principal extent (side of the equivalent uniform rectangle) of at least
  // this many metres (0.7: with 1.0 the desks of s_static, which the seated people's arms touch,
  // were completed into their masks: 35 000 wrong pixels a frame against 10 700 with 0.7, seed
  // 25, exact masks; 0.5 starts to take flat bodies for structure).
  double min_side_m = 0.7;
  uint32_t seed = 1;
  void Check() const;  // InputError naming the field
};

class StructurePlanes {
 public:
  // Planes of `depth` (CV_32FC1 metres, 0 / non-finite invalid), ideal pinhole pixels of
  // `camera`. Pixels under a non-zero `exclude` (CV_8UC1, or empty) are not sampled: a masked
  // body is never taken for structure.
  static StructurePlanes Find(const cv::Mat& depth, const camera::PinholeCamera& camera,
                              const cv::Mat& exclude, const StructurePlaneOptions& options);

  // Whether pixel (u, v) with depth z (metres) lies on a found plane, within its part on the grid
  // (dilated by one cell) and within the inlier distance.
  bool Contains(int u, int v, float z) const;

  int size() const { return static_cast<int>(planes_.size()); }
  // Unit normal n and offset d of plane i (n . X + d = 0, camera frame).
  const Eigen::Vector4d& plane(int i) const { return planes_[i].coefficients; }

 private:
  StructurePlanes(const camera::PinholeCamera& camera, const StructurePlaneOptions& options)
      : camera_(camera), options_(options) {}
  // The camera-frame point of pixel (u, v) at depth z (ideal pinhole).
  Eigen::Vector3d Point(int u, int v, float z) const;

  struct Plane {
    Eigen::Vector4d coefficients;
    cv::Mat cells;  // CV_8UC1 grid, 255 where the part (dilated by one cell) lies
  };
  camera::PinholeCamera camera_;
  StructurePlaneOptions options_;
  std::vector<Plane> planes_;
  cv::Mat cell_planes_;  // CV_8UC1 grid: bit k set where plane k's part lies
};

}  // namespace moslam::feature
