// Mask regions around clusters of inconsistent keypoints (moving_regions.h).
#include "moslam/slam/moving_regions.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

// Union-find over keypoint indices.
int Find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

bool Linked(const InconsistentKeypoint& a, const InconsistentKeypoint& b,
            const MovingRegionOptions& o) {
  const cv::Point2f d = a.pixel - b.pixel;
  if (d.x * d.x + d.y * d.y > o.link_px * o.link_px) return false;
  if (a.depth <= 0.0f || b.depth <= 0.0f) return true;
  const double z = std::min(a.depth, b.depth);
  return std::abs(a.depth - b.depth) <= o.link_depth_abs + o.link_depth_rel * z;
}

// One cluster's region: discs and hull, limited to its depth range where depth is measured.
void DrawRegion(const std::vector<InconsistentKeypoint>& keypoints, const std::vector<int>& members,
                const cv::Mat& depth, const MovingRegionOptions& o, cv::Mat* out) {
  cv::Mat region = cv::Mat::zeros(out->size(), CV_8UC1);
  std::vector<cv::Point> points;
  float zmin = std::numeric_limits<float>::max(), zmax = 0.0f;
  for (int i : members) {
    const cv::Point p(cvRound(keypoints[i].pixel.x), cvRound(keypoints[i].pixel.y));
    points.push_back(p);
    cv::circle(region, p, o.radius_px, cv::Scalar(255), cv::FILLED);
    if (keypoints[i].depth > 0.0f) {
      zmin = std::min(zmin, keypoints[i].depth);
      zmax = std::max(zmax, keypoints[i].depth);
    }
  }
  std::vector<cv::Point> hull;
  cv::convexHull(points, hull);
  cv::fillConvexPoly(region, hull, cv::Scalar(255));
  // Everything drawn lies within the points' box grown by the disc radius: only that part of
  // the image is visited (the whole image per cluster was 80 % of the cost).
  const cv::Rect box = (cv::boundingRect(points) + cv::Point(-o.radius_px - 1, -o.radius_px - 1) +
                        cv::Size(2 * o.radius_px + 3, 2 * o.radius_px + 3)) &
                       cv::Rect(0, 0, region.cols, region.rows);
  if (!depth.empty() && zmax > 0.0f) {
    const float lo = zmin - static_cast<float>(o.depth_margin);
    const float hi = zmax + static_cast<float>(o.depth_margin);
    for (int v = box.y; v < box.y + box.height; ++v) {
      auto* r = region.ptr<uint8_t>(v);
      const auto* z = depth.ptr<float>(v);
      for (int u = box.x; u < box.x + box.width; ++u) {
        // Measured depth outside the range: the static surface behind (or in front of) it.
        if (r[u] != 0 && z[u] > 0.0f && (z[u] < lo || z[u] > hi)) r[u] = 0;
      }
    }
  }
  cv::Mat target = (*out)(box);
  cv::bitwise_or(target, region(box), target);
}

}  // namespace

void MovingRegionOptions::Check() const {
  if (min_points < 2)
    ThrowInput("MovingRegionOptions.min_points must be >= 2 (got {})", min_points);
  if (!(link_px > 0.0f)) ThrowInput("MovingRegionOptions.link_px must be > 0 (got {})", link_px);
  if (!(link_depth_abs >= 0.0) || !(link_depth_rel >= 0.0) || !(depth_margin >= 0.0)) {
    ThrowInput("MovingRegionOptions: link_depth_abs, link_depth_rel and depth_margin must be >= 0");
  }
  if (radius_px < 0 || radius_px > 200) {
    ThrowInput("MovingRegionOptions.radius_px must be in 0..200 (got {})", radius_px);
  }
}

cv::Mat MovingRegions(const std::vector<InconsistentKeypoint>& keypoints, const cv::Mat& depth,
                      const cv::Size& size, const MovingRegionOptions& options) {
  MOSLAM_CHECK(depth.empty() || (depth.type() == CV_32FC1 && depth.size() == size));
  const int n = static_cast<int>(keypoints.size());
  if (n < options.min_points) return cv::Mat();
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  // O(n^2) pairs: n is the frame's inconsistent keypoints, tens to a few hundred.
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (Linked(keypoints[i], keypoints[j], options)) parent[Find(parent, i)] = Find(parent, j);
    }
  }
  std::vector<std::vector<int>> clusters(n);
  for (int i = 0; i < n; ++i) clusters[Find(parent, i)].push_back(i);
  cv::Mat mask;
  for (const std::vector<int>& members : clusters) {
    if (static_cast<int>(members.size()) < options.min_points) continue;
    if (mask.empty()) mask = cv::Mat::zeros(size, CV_8UC1);
    DrawRegion(keypoints, members, depth, options, &mask);
  }
  if (!mask.empty() && cv::countNonZero(mask) == 0) return cv::Mat();
  return mask;
}

}  // namespace moslam::slam
