// Evidence that map points lie on movable objects (movable_points.h).
#include "moslam/slam/movable_points.h"

#include <cmath>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void MovablePointsOptions::Check() const {
  if (mask_threshold < 1) throw InputError("MovablePointsOptions.mask_threshold must be >= 1");
  if (free_space_threshold < 1) {
    throw InputError("MovablePointsOptions.free_space_threshold must be >= 1");
  }
  if (!(depth_abs >= 0.0) || !(depth_rel >= 0.0)) {
    throw InputError("MovablePointsOptions.depth_abs and depth_rel must be >= 0");
  }
  if (free_space_window < 0) {
    throw InputError("MovablePointsOptions.free_space_window must be >= 0");
  }
  if (max_observations_without_depth < 0) {
    throw InputError("MovablePointsOptions.max_observations_without_depth must be >= 0");
  }
}

namespace {

bool ValidDepth(float z) { return z > 0.0f && std::isfinite(z); }

// Every valid depth of the window behind `z` + tol, and at least half the window valid.
bool FreeSpaceAround(const cv::Mat& depth, int u, int v, int w, double z, double tol) {
  int valid = 0, total = 0;
  for (int y = v - w; y <= v + w; ++y) {
    for (int x = u - w; x <= u + w; ++x) {
      ++total;
      if (x < 0 || y < 0 || x >= depth.cols || y >= depth.rows) continue;
      const float d = depth.at<float>(y, x);
      if (!ValidDepth(d)) continue;
      if (d <= z + tol) return false;
      ++valid;
    }
  }
  return 2 * valid >= total;
}

}  // namespace

MovablePointsStats JudgeMovablePoints(map::Map* map,
                                      const std::vector<std::shared_ptr<map::MapPoint>>& points,
                                      const JudgingFrame& frame,
                                      const camera::PinholeCamera& camera,
                                      const MovablePointsOptions& options) {
  MOSLAM_CHECK(map != nullptr);
  MovablePointsStats stats;
  const bool has_mask = options.mask_evidence && !frame.mask.empty();
  const bool has_depth = !frame.depth.empty();
  if (!has_mask && !(options.free_space_evidence && has_depth)) return stats;
  const cv::Size size = has_mask ? frame.mask.size() : frame.depth.size();
  const Eigen::Vector3d centre = frame.T_cam_world.Inverse().translation();
  for (const auto& p : points) {
    if (!p || p->bad) continue;
    const Eigen::Vector3d pc = frame.T_cam_world * p->position;
    const auto px = camera.Project(pc);  // the raw image's pixel: masks and depth live there
    if (!px) continue;
    const int u = static_cast<int>(std::lround(px->x()));
    const int v = static_cast<int>(std::lround(px->y()));
    if (u < 0 || v < 0 || u >= size.width || v >= size.height) continue;
    const double z = pc.z();
    const double tol = options.depth_abs + options.depth_rel * z;
    const float measured = has_depth ? frame.depth.at<float>(v, u) : 0.0f;
    bool erase = false;
    if (has_mask && frame.mask.at<uint8_t>(v, u) != 0) {
      // With depth: only on the surface the mask calls movable. Behind it (a static point that
      // a body occludes), in front of it, or where the depth is invalid (a body's silhouette
      // has many such pixels) tells nothing.
      const bool counts = has_depth
                              ? ValidDepth(measured) && std::abs(measured - z) <= tol
                              : p->num_observations() <= options.max_observations_without_depth;
      if (counts) {
        ++stats.mask_hits;
        erase = ++p->movable_evidence >= options.mask_threshold;
      }
    } else if (options.free_space_evidence && has_depth) {
      // Only where the point should be seen (ORB-SLAM2's isInFrustum: scale range, viewing
      // angle within 60 degrees of its mean direction).
      const Eigen::Vector3d ray = p->position - centre;
      const double dist = ray.norm();
      const bool visible = dist >= 0.8 * p->min_distance && dist <= 1.2 * p->max_distance &&
                           ray.dot(p->normal) >= 0.5 * dist;
      if (visible && FreeSpaceAround(frame.depth, u, v, options.free_space_window, z, tol)) {
        ++stats.free_space_hits;
        erase = ++p->free_space_evidence >= options.free_space_threshold;
      }
    }
    if (erase) {
      map->EraseMapPoint(p);
      ++stats.erased;
    }
  }
  return stats;
}

}  // namespace moslam::slam
