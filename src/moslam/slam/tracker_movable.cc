// The Tracker's part in handling movable objects (issue 24): judging the local map's points by
// each frame's mask and depth (slam/movable_points.h), and the moving-keypoint check of new
// keyframes (slam/moving_keypoints.h). Same locking as tracker.cc: called under Map::mutex().
#include <algorithm>
#include <set>

#include <spdlog/spdlog.h>

#include "moslam/slam/moving_keypoints.h"
#include "moslam/slam/tracker.h"

namespace moslam::slam {

MovablePointsStats Tracker::JudgeLocalPoints(const FrameImages& images) {
  if (images.mask.empty() && images.depth.empty()) return {};
  std::set<uint64_t> matched;
  for (size_t i = 0; i < current_.points.size(); ++i) {
    if (current_.points[i] && !current_.outlier[i]) matched.insert(current_.points[i]->id);
  }
  std::vector<std::shared_ptr<map::MapPoint>> unmatched;
  unmatched.reserve(local_points_.size());
  for (const auto& p : local_points_) {
    if (!p->bad && !matched.count(p->id)) unmatched.push_back(p);
  }
  return JudgeMovablePoints(map_, unmatched, {current_.T_cam_world, images.mask, images.depth},
                            camera_, options_.movable);
}

void Tracker::FlagMovingKeypoints() {
  if (!options_.moving.enabled ||
      recent_frames_.size() != static_cast<size_t>(options_.moving.frame_gap)) {
    return;
  }
  const auto& [earlier, T_earlier_world] = recent_frames_.front();
  current_.frame.moving = FindMovingKeypoints(current_.frame, current_.T_cam_world, earlier,
                                              T_earlier_world, camera_, options_.moving);
  spdlog::debug("keyframe at {:.3f}: {} of {} keypoints seen moving", current_.frame.timestamp,
                std::count(current_.frame.moving.begin(), current_.frame.moving.end(), 1),
                current_.frame.size());
}

void Tracker::RememberFrame() {
  if (!options_.moving.enabled) return;
  recent_frames_.emplace_back(current_.frame, current_.T_cam_world);
  while (recent_frames_.size() > static_cast<size_t>(options_.moving.frame_gap)) {
    recent_frames_.pop_front();
  }
}

}  // namespace moslam::slam
