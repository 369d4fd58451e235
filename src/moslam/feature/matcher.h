// ORB descriptor matching without map classes, after ORB-SLAM2's ORBmatcher (Mur-Artal & Tardós
// 2017): brute-force matching between two keypoint sets with a ratio test and a rotation
// consistency check, and guided matching of projected 3D points in a frame's grid.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "moslam/feature/frame.h"

namespace moslam::feature {

// ORB-SLAM2's thresholds (Hamming distance of 256-bit descriptors).
inline constexpr int kThLow = 50;
inline constexpr int kThHigh = 100;
// Bins of the rotation-consistency histogram (12 degrees each).
inline constexpr int kRotationBins = 30;

struct DescriptorMatch {
  int index1 = -1;  // into the first set
  int index2 = -1;  // into the second set
  int distance = 0;
};

struct DescriptorMatchOptions {
  int max_distance = kThLow;  // accept best distance <= this
  float ratio = 0.6f;         // best < ratio * second best (ORB-SLAM2's SearchByBoW default)
  // Keep only matches whose keypoint angle difference falls in the three most populated bins of a
  // 30-bin histogram (bins under 10% of the largest dropped): a rigid image motion rotates all
  // keypoints alike, so the other bins are mostly wrong matches.
  bool check_orientation = true;
  void Check() const;  // InputError for distance outside [0, 256] or ratio outside (0, 1]
};

// Brute force over all pairs. Each index2 is used at most once (the smaller distance wins).
// Sorted by index1.
std::vector<DescriptorMatch> MatchByDescriptor(const std::vector<cv::KeyPoint>& keypoints1,
                                               const cv::Mat& descriptors1,
                                               const std::vector<cv::KeyPoint>& keypoints2,
                                               const cv::Mat& descriptors2,
                                               const DescriptorMatchOptions& options = {});

// The same between two frames, on their undistorted keypoints.
inline std::vector<DescriptorMatch> MatchByDescriptor(const Frame& frame1, const Frame& frame2,
                                                      const DescriptorMatchOptions& options = {}) {
  return MatchByDescriptor(frame1.keypoints_undistorted, frame1.descriptors,
                           frame2.keypoints_undistorted, frame2.descriptors, options);
}

// Given the per-match angle difference (degrees), returns a keep-flag per entry according to the
// rotation histogram rule above. Exposed for the map-level matchers that come later.
std::vector<bool> RotationConsistent(const std::vector<float>& angle_differences);

// A 3D point as seen from the frame: predicted (undistorted) pixel, pyramid level and the point's
// representative descriptor (32 bytes, must stay valid during the call).
struct ProjectedPoint {
  Eigen::Vector2f pixel;
  int octave = 0;
  const uint8_t* descriptor = nullptr;
  float u_right = -1.0f;  // predicted right coordinate (stereo/RGB-D); < 0: not checked
};

struct ProjectionMatchOptions {
  // Search radius at level 0 in pixels; multiplied by the predicted level's scale factor
  // (ORB-SLAM2: th = 1 in tracking, larger after relocalisation).
  float radius = 1.0f;
  int max_distance = kThHigh;  // accept best distance <= this
  // Best must be below ratio * second best when both lie on the same level (ORB-SLAM2: 0.8).
  float ratio = 0.8f;
  void Check() const;
};

// For each point, the matched keypoint index of `frame`, or -1. Candidates are keypoints within
// the scaled radius on levels [octave - 1, octave]; a keypoint with a known u_right must also
// agree with the point's predicted u_right within the radius. A keypoint claimed by several
// points keeps the point with the smallest distance.
std::vector<int> MatchByProjection(const Frame& frame, const std::vector<ProjectedPoint>& points,
                                   const ProjectionMatchOptions& options = {});

}  // namespace moslam::feature
