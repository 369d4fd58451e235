// Keypoints seen moving between two tracked frames (moving_keypoints.h).
#include "moslam/slam/moving_keypoints.h"

#include <cmath>
#include <limits>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void MovingKeypointsOptions::Check() const {
  if (frame_gap < 1) throw InputError("MovingKeypointsOptions.frame_gap must be >= 1");
  if (!(static_radius > 0.0f) || !(search_radius > static_radius)) {
    throw InputError(
        "MovingKeypointsOptions: static_radius must be > 0 and search_radius > static_radius");
  }
  if (max_distance < 0 || max_distance > 256) {
    throw InputError("MovingKeypointsOptions.max_distance must be in 0..256");
  }
  if (!(depth_abs >= 0.0) || !(depth_rel >= 0.0)) {
    throw InputError("MovingKeypointsOptions.depth_abs and depth_rel must be >= 0");
  }
}

std::vector<uint8_t> FindMovingKeypoints(const feature::Frame& current,
                                         const geometry::SE3& T_current_world,
                                         const feature::Frame& earlier,
                                         const geometry::SE3& T_earlier_world,
                                         const camera::PinholeCamera& camera,
                                         const MovingKeypointsOptions& options) {
  std::vector<uint8_t> moving(current.size(), 0);
  if (!options.enabled || earlier.size() == 0) return moving;
  const geometry::SE3 T_earlier_current = T_earlier_world * T_current_world.Inverse();
  for (size_t i = 0; i < current.size(); ++i) {
    const auto p_cur = current.UnprojectCamera(i, camera);
    if (!p_cur) continue;
    const Eigen::Vector3d p = T_earlier_current * *p_cur;
    if (p.z() <= 0.0) continue;
    const double u = camera.fx() * p.x() / p.z() + camera.cx();
    const double v = camera.fy() * p.y() / p.z() + camera.cy();
    const int level = current.keypoints[i].octave;
    const float scale = current.scale_factors.empty() ? 1.0f : current.scale_factors[level];
    const float static_r = options.static_radius * scale;
    // The search within static_r first: most keypoints are static and are decided by it, and
    // only a keypoint without a match there needs the wide search (15-20x the candidates). The
    // result is the one of a single wide search: the near candidates come in the same order (the
    // narrow box is 1 px wider than static_r, so float rounding of the box test drops none).
    int best_near = std::numeric_limits<int>::max(), best_far = best_near;
    size_t near_index = 0;
    for (const bool wide : {false, true}) {
      const std::vector<size_t> nearby = earlier.FeaturesInArea(
          static_cast<float>(u), static_cast<float>(v),
          wide ? options.search_radius * scale : static_r + 1.0f, level - 1, level + 1);
      for (size_t j : nearby) {
        const int d = feature::DescriptorDistance(current.descriptor(i), earlier.descriptor(j));
        if (d > options.max_distance) continue;
        const cv::Point2f& q = earlier.keypoints_undistorted[j].pt;
        const double r = std::hypot(q.x - u, q.y - v);
        if (r <= static_r) {
          if (d < best_near) best_near = d, near_index = j;
        } else if (wide) {
          best_far = std::min(best_far, d);
        }
      }
      if (best_near <= options.max_distance) break;
    }
    if (best_near <= options.max_distance) {
      // Found where a static point would be; with depth, at the depth it would have there.
      const float z = earlier.depth.empty() ? -1.0f : earlier.depth[near_index];
      const double tol = options.depth_abs + options.depth_rel * p.z();
      if (z > 0.0f && std::abs(z - p.z()) > tol) moving[i] = 1;
    } else if (best_far <= options.max_distance) {
      moving[i] = 1;  // found only elsewhere: it moved
    }
  }
  return moving;
}

}  // namespace moslam::slam
