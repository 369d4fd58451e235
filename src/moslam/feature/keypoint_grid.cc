#include "moslam/feature/keypoint_grid.h"

#include <algorithm>
#include <cmath>

#include "moslam/util/check.h"

namespace moslam::feature {

KeypointGrid::KeypointGrid(const ImageBounds& bounds, const std::vector<cv::KeyPoint>& keypoints)
    : bounds_(bounds), cells_(kGridCols * kGridRows) {
  MOSLAM_CHECK(bounds.max_x > bounds.min_x && bounds.max_y > bounds.min_y) << "empty image bounds";
  inv_cell_width_ = kGridCols / (bounds.max_x - bounds.min_x);
  inv_cell_height_ = kGridRows / (bounds.max_y - bounds.min_y);
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::Point2f& pt = keypoints[i].pt;
    cells_[CellY(pt.y) * kGridCols + CellX(pt.x)].push_back(i);
  }
}

// Floor then clamp: monotone in x, so a search range maps to a contiguous cell range that holds
// every keypoint inside it (ORB-SLAM2 rounds and drops keypoints rounding off the grid).
int KeypointGrid::CellX(float x) const {
  const float cell = std::floor((x - bounds_.min_x) * inv_cell_width_);
  return static_cast<int>(std::clamp(cell, 0.0f, static_cast<float>(kGridCols - 1)));
}

int KeypointGrid::CellY(float y) const {
  const float cell = std::floor((y - bounds_.min_y) * inv_cell_height_);
  return static_cast<int>(std::clamp(cell, 0.0f, static_cast<float>(kGridRows - 1)));
}

std::vector<size_t> KeypointGrid::FeaturesInArea(const std::vector<cv::KeyPoint>& keypoints,
                                                 float x, float y, float r, int min_level,
                                                 int max_level) const {
  std::vector<size_t> indices;
  if (cells_.empty() || !(r >= 0.0f) || !std::isfinite(x) || !std::isfinite(y)) return indices;
  const int col_end = CellX(x + r);
  const int row_end = CellY(y + r);
  for (int row = CellY(y - r); row <= row_end; ++row) {
    for (int col = CellX(x - r); col <= col_end; ++col) {
      for (const size_t i : cells_[row * kGridCols + col]) {
        const cv::KeyPoint& kp = keypoints[i];
        if (min_level > 0 && kp.octave < min_level) continue;
        if (max_level >= 0 && kp.octave > max_level) continue;
        if (std::abs(kp.pt.x - x) <= r && std::abs(kp.pt.y - y) <= r) indices.push_back(i);
      }
    }
  }
  return indices;
}

}  // namespace moslam::feature
