// Mask regions of things seen moving, found by geometry alone (issue 24, "a cluster of
// inconsistent points becomes a mask region of its own"; CFP-SLAM and DynaSLAM grow regions
// from dynamic keypoints the same way). Keypoints that tracking found inconsistent with the
// camera's motion (matched map points judged moving by their residuals, static_scores.h, and
// keyframe keypoints seen moving, moving_keypoints.h) are clustered by image distance and depth;
// a cluster of min_points or more becomes a region: the disc of `radius_px` around each of its
// keypoints, their convex hull, limited (where depth is measured) to the cluster's depth range
// plus a margin, so the static surface behind or in front stays free. The regions are carried
// into the next frames like a network's mask (mask_propagation.h): the extractor stays off the
// mover, and no map point is made on it, with no network that knows its class.
// A lone inconsistent keypoint (a bad match, depth noise) makes no region.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace moslam::slam {

struct MovingRegionOptions {
  int min_points = 5;            // keypoints a cluster needs to become a region (>= 2)
  float link_px = 40.0f;         // two keypoints join a cluster within this distance (pixels) ...
  double link_depth_abs = 0.15;  // ... and depth difference abs + rel * depth (metres)
  double link_depth_rel = 0.1;
  int radius_px = 12;          // disc around each keypoint, and the hull's margin
  double depth_margin = 0.15;  // region pixels: depth within the cluster's range +- this (m)
  void Check() const;          // InputError naming the field
};

struct InconsistentKeypoint {
  cv::Point2f pixel;   // distorted (raw image) coordinates, where the mask applies
  float depth = 0.0f;  // metres; <= 0: none (joins clusters by distance only, adds no depth)
};

// CV_8UC1 0/255 of `size`, or empty when no cluster is large enough. `depth` (CV_32FC1 metres
// of the image, or empty) limits the regions to the clusters' depth ranges.
cv::Mat MovingRegions(const std::vector<InconsistentKeypoint>& keypoints, const cv::Mat& depth,
                      const cv::Size& size, const MovingRegionOptions& options);

}  // namespace moslam::slam
