// Map points on movable objects, found after the fact (issue 24). A per-frame mask keeps the
// extractor off the bodies it covers, but where a weak network misses part of a body (at the
// image's border, as people enter or leave, on frames where its recall drops) map points are
// made on it, and once in the map they pull the tracker along with the body. Such points give
// themselves away later:
//  - mask evidence: the point projects into a later frame's movable mask, at the depth that
//    frame measures there (RGB-D; a static point behind a passing body is occluded, nearer
//    depth, and gains nothing, as does one where the depth is invalid). Without depth (stereo,
//    monocular) only young points (few observations) count: a static point seen from many keyframes
//    is kept even when a body passes in front of it. DynaSLAM and DS-SLAM drop such points per
//    frame; keeping the count on the point removes them from the map for good.
//  - free-space evidence (RGB-D): the point should be visible (in the frustum, in its scale
//    range, seen from its side) but the frame measures a surface clearly behind it over a small
//    window: the space it claims to occupy is empty. That is how a point on a body that walked
//    away shows, mask or no mask (DynaSLAM's multi-view depth test, in the tracked frame).
// A point past a threshold of either is erased with its observations, so it is never matched
// again. Points matched as inliers in the frame are not judged by it.
//
// Caller holds Map::mutex().
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/se3.h"
#include "moslam/map/map.h"

namespace moslam::slam {

struct MovablePointsOptions {
  bool mask_evidence = true;  // points seen inside a movable mask
  // RGB-D: points in front of the measured surface; off as SystemOptions::free_space_evidence
  bool free_space_evidence = false;
  int mask_threshold = 2;        // frames of mask evidence that erase a point
  int free_space_threshold = 3;  // frames of free-space evidence that erase a point
  // Depth agreement: |measured - point depth| <= depth_abs + depth_rel * depth (metres).
  double depth_abs = 0.05;
  double depth_rel = 0.03;
  // Free space: every valid depth in the (2w+1)^2 window around the projection is behind the
  // point by more than the tolerance, and at least half the window is valid (pixels).
  int free_space_window = 2;
  // Without depth: points with more observations than this are never judged by a mask.
  int max_observations_without_depth = 4;
  void Check() const;  // InputError naming the field
};

struct MovablePointsStats {
  int mask_hits = 0;        // points that gained mask evidence
  int free_space_hits = 0;  // points that gained free-space evidence
  int erased = 0;           // points erased
};

// The frame the points are judged by: its pose, its mask (CV_8UC1 raw image, non-zero =
// movable; empty = none) and its depth (CV_32FC1 metres registered to the image; empty = none).
struct JudgingFrame {
  geometry::SE3 T_cam_world;
  cv::Mat mask;
  cv::Mat depth;
};

// Adds evidence to each of `points` (points the frame did not match; bad ones are skipped) and
// erases those past a threshold (Map::EraseMapPoint).
MovablePointsStats JudgeMovablePoints(map::Map* map,
                                      const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                      const JudgingFrame& frame,
                                      const camera::PinholeCamera& camera,
                                      const MovablePointsOptions& options);

}  // namespace moslam::slam
