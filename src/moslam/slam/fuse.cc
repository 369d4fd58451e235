#include "moslam/slam/fuse.h"

#include <climits>
#include <cmath>
#include <set>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/feature/matcher.h"

namespace moslam::slam {

namespace {

// Keypoint of `kf` that best matches `point` projected into it, or -1.
int BestKeypoint(const map::KeyFrame& kf, const map::MapPoint& point,
                 const camera::PinholeCamera& cam, float radius_px) {
  const Eigen::Vector3d p = kf.T_cam_world() * point.position;
  if (p.z() <= 0.0) return -1;
  const double u = cam.fx() * p.x() / p.z() + cam.cx();
  const double v = cam.fy() * p.y() / p.z() + cam.cy();
  const auto& b = kf.frame.bounds;
  if (u < b.min_x || u > b.max_x || v < b.min_y || v > b.max_y) return -1;
  const Eigen::Vector3d po = point.position - kf.CameraCenter();
  const double dist = po.norm();
  // Inside the scale-invariance range and seen from less than 60 degrees off its mean direction.
  if (dist < 0.8 * point.min_distance || dist > 1.2 * point.max_distance) return -1;
  if (po.dot(point.normal) < 0.5 * dist) return -1;
  if (point.descriptor.empty()) return -1;
  const int num_levels = kf.frame.num_levels();
  const float log_scale = std::log(kf.frame.scale_factors.at(std::min(1, num_levels - 1)));
  const int level = point.PredictScale(static_cast<float>(dist), log_scale, num_levels);
  const float radius = radius_px * kf.frame.scale_factors[level];
  const double ur = u - kf.frame.bf / p.z();
  int best_dist = INT_MAX;
  int best = -1;
  for (size_t i : kf.frame.FeaturesInArea(static_cast<float>(u), static_cast<float>(v), radius)) {
    const cv::KeyPoint& kp = kf.frame.keypoints_undistorted[i];
    if (kp.octave < level - 1 || kp.octave > level) continue;
    const double ex = u - kp.pt.x, ey = v - kp.pt.y;
    double e2 = ex * ex + ey * ey;
    const float kp_ur = kf.frame.u_right[i];
    const bool stereo = kp_ur >= 0.0f;
    if (stereo) e2 += (ur - kp_ur) * (ur - kp_ur);
    if (e2 * kf.frame.inv_level_sigma2[kp.octave] > (stereo ? 7.8 : 5.99)) continue;
    const int d =
        feature::DescriptorDistance(point.descriptor.ptr<uint8_t>(), kf.frame.descriptor(i));
    if (d < best_dist) best_dist = d, best = static_cast<int>(i);
  }
  return best_dist <= feature::kThLow ? best : -1;
}

}  // namespace

int Fuse(map::Map* map, const std::shared_ptr<map::KeyFrame>& kf,
         const std::vector<std::shared_ptr<map::MapPoint>>& points,
         const camera::PinholeCamera& camera, float radius_px) {
  int fused = 0;
  // By value: Map::Replace rewrites keyframes' point slots, and `points` may be one of them.
  for (size_t k = 0; k < points.size(); ++k) {
    const std::shared_ptr<map::MapPoint> point = points[k];
    if (!point || point->bad || point->IsObservedBy(kf->id)) continue;
    const int i = BestKeypoint(*kf, *point, camera, radius_px);
    if (i < 0) continue;
    const std::shared_ptr<map::MapPoint> existing = kf->points[i];
    if (existing && !existing->bad) {
      if (existing->num_observations() > point->num_observations()) {
        map->Replace(point, existing);
      } else {
        map->Replace(existing, point);
      }
    } else {
      point->AddObservation(kf, static_cast<size_t>(i));
      kf->points[i] = point;
    }
    ++fused;
  }
  return fused;
}

void SearchInNeighbors(map::Map* map, const std::shared_ptr<map::KeyFrame>& kf,
                       const camera::PinholeCamera& camera, int num_neighbours) {
  std::vector<std::shared_ptr<map::KeyFrame>> targets;
  std::set<uint64_t> seen = {kf->id};
  for (const auto& n : kf->BestCovisibles(num_neighbours)) {
    if (!seen.insert(n->id).second) continue;
    targets.push_back(n);
  }
  const size_t first_ring = targets.size();
  for (size_t t = 0; t < first_ring; ++t) {
    for (const auto& n2 : targets[t]->BestCovisibles(5)) {
      if (seen.insert(n2->id).second) targets.push_back(n2);
    }
  }
  const std::vector<std::shared_ptr<map::MapPoint>> own = kf->points;  // Fuse rewrites kf->points
  for (const auto& target : targets) Fuse(map, target, own, camera);
  std::vector<std::shared_ptr<map::MapPoint>> candidates;
  std::set<uint64_t> candidate_ids;
  for (const auto& target : targets) {
    for (const auto& p : target->points) {
      if (!p || p->bad || p->IsObservedBy(kf->id)) continue;
      if (candidate_ids.insert(p->id).second) candidates.push_back(p);
    }
  }
  Fuse(map, kf, candidates, camera);
  for (const auto& p : kf->points) {
    if (!p || p->bad) continue;
    p->ComputeDistinctiveDescriptor();
    p->UpdateNormalAndDepth();
  }
  kf->UpdateConnections();
}

}  // namespace moslam::slam
