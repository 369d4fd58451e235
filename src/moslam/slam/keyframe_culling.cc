#include "moslam/slam/keyframe_culling.h"

namespace moslam::slam {

namespace {
constexpr int kMinOtherObservers = 3;
constexpr double kRedundantFraction = 0.9;
}  // namespace

bool IsRedundant(const map::KeyFrame& kf, const map::Map& map, double close_depth_m) {
  int num_points = 0;
  int num_redundant = 0;
  for (size_t i = 0; i < kf.points.size(); ++i) {
    const auto& p = kf.points[i];
    if (!p || p->bad) continue;
    if (close_depth_m > 0.0 && kf.frame.bf > 0.0) {
      const float depth = kf.frame.depth[i];
      if (depth <= 0.0f || depth > close_depth_m) continue;
    }
    ++num_points;
    if (p->num_observations() <= kMinOtherObservers) continue;
    const int level = kf.frame.keypoints_undistorted[i].octave;
    int others = 0;
    for (const auto& [other_id, obs] : p->observations()) {
      if (other_id == kf.id) continue;
      const auto other = map.keyframe(other_id);
      if (!other) continue;
      if (other->frame.keypoints_undistorted[obs.index].octave <= level + 1) ++others;
      if (others >= kMinOtherObservers) break;
    }
    if (others >= kMinOtherObservers) ++num_redundant;
  }
  return num_points > 0 && num_redundant > kRedundantFraction * num_points;
}

int CullRedundantKeyFrames(map::Map* map, const std::shared_ptr<map::KeyFrame>& kf,
                           double close_depth_m) {
  int erased = 0;
  for (const auto& other : kf->BestCovisibles(-1)) {
    if (other->id == 0 || other->bad() || !other->parent()) continue;
    if (IsRedundant(*other, *map, close_depth_m)) {
      map->EraseKeyFrame(other);
      ++erased;
    }
  }
  return erased;
}

}  // namespace moslam::slam
