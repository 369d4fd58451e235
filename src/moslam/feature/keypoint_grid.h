// A uniform grid over the undistorted image bounds that buckets keypoints for radius search, as
// ORB-SLAM2's Frame does (64 x 48 cells, Mur-Artal & Tardós 2017): matching by projection asks
// "which keypoints lie near this predicted pixel?" hundreds of times per frame.
#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::feature {

inline constexpr int kGridCols = 64;
inline constexpr int kGridRows = 48;

// The rectangle, in undistorted pixels, that the image covers (ORB-SLAM2's ComputeImageBounds).
struct ImageBounds {
  float min_x = 0.0f;
  float max_x = 0.0f;
  float min_y = 0.0f;
  float max_y = 0.0f;
};

class KeypointGrid {
 public:
  KeypointGrid() = default;
  // Buckets `keypoints` (undistorted positions). A keypoint outside `bounds` (possible with strong
  // distortion) goes to the nearest border cell, so that no keypoint is lost from the search.
  // Bounds must have positive width and height (CHECK).
  KeypointGrid(const ImageBounds& bounds, const std::vector<cv::KeyPoint>& keypoints);

  // Indices of the keypoints with |x' - x| <= r and |y' - y| <= r (ORB-SLAM2's square window,
  // not a disc) whose octave is in [min_level, max_level]; min_level <= 0 means no lower bound,
  // max_level < 0 no upper bound. `keypoints` must be the vector the grid was built from.
  std::vector<size_t> FeaturesInArea(const std::vector<cv::KeyPoint>& keypoints, float x, float y,
                                     float r, int min_level = 0, int max_level = -1) const;

  const ImageBounds& bounds() const { return bounds_; }

 private:
  int CellX(float x) const;
  int CellY(float y) const;

  ImageBounds bounds_;
  float inv_cell_width_ = 0.0f;
  float inv_cell_height_ = 0.0f;
  // cells_[row * kGridCols + col] lists keypoint indices.
  std::vector<std::vector<size_t>> cells_;
};

}  // namespace moslam::feature
