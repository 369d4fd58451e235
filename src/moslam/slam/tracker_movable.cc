// The Tracker's part in handling movable objects (issue 24): judging the local map's points by
// each frame's mask and depth (slam/movable_points.h), the moving-keypoint check of new
// keyframes (slam/moving_keypoints.h), and the established-points check of each pose
// (slam/young_points.h). Same locking as tracker.cc: called under Map::mutex().
#include <algorithm>
#include <set>

#include <spdlog/spdlog.h>

#include "moslam/optim/observation.h"
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

void Tracker::CheckYoungPoints(const std::vector<size_t>& index,
                               const std::vector<Eigen::Vector3d>& points,
                               const geometry::SE3& start, optim::PoseOptimizerResult* result) {
  if (!options_.young_points.enabled) return;
  std::vector<double> ages(index.size());
  const double t = current_.frame.timestamp;
  for (size_t k = 0; k < index.size(); ++k) {
    ages[k] = static_scores_.Age(current_.points[index[k]]->id, t);
  }
  // Without a motion-model prediction (the reference keyframe's matches, relocalization) the
  // prior is where the optimization started.
  YoungPointResult check = young_points_.Check(model_, current_.frame, index, points, ages, *result,
                                               prediction_.value_or(start), options_.num_threads);
  if (!check.moving) return;
  young_points_moved_ = true;
  spdlog::debug(
      "frame at {:.3f}: {} of {} young points move apart from the established ones (excess "
      "{:.1f}, prior sigma {:.4f} m {:.4f} rad); left out of the pose",
      t, std::count(check.excluded.begin(), check.excluded.end(), true), check.num_young,
      check.excess, young_points_.PriorSigma()[0], young_points_.PriorSigma()[1]);
  *result = std::move(check.pose);
}

int Tracker::JudgeResiduals(std::vector<InconsistentKeypoint>* inconsistent) {
  int matched = 0, inliers = 0;
  for (size_t i = 0; i < current_.points.size(); ++i) {
    if (!current_.points[i]) continue;
    ++matched;
    if (current_.outlier[i]) continue;
    ++inliers;
    // How long each point has been known (its vote in the pose consensus), scores on or off.
    static_scores_.Seen(current_.points[i], current_.frame.timestamp);
  }
  if (!options_.static_scores.enabled) return 0;
  // Residuals judge points only against a pose most matches agree with: a frame where tracking
  // is shaky (few inliers, or as many outliers as inliers) would make static points look moving.
  if (inliers < 2 * options_.min_inliers || 2 * inliers < matched) return 0;
  int erased = 0;
  const feature::Frame& f = current_.frame;
  for (size_t i = 0; i < current_.points.size(); ++i) {
    const std::shared_ptr<map::MapPoint> p = current_.points[i];
    if (!p || p->bad) continue;
    const double threshold = f.u_right[i] >= 0.0f ? optim::kChi2Stereo : optim::kChi2Mono;
    const double probability = static_scores_.Observe(p, current_chi2_[i], threshold);
    if (current_.outlier[i] && probability < 0.5) {
      inconsistent->push_back({f.keypoints[i].pt, f.depth.empty() ? 0.0f : f.depth[i]});
    }
    if (!options_.localization && static_scores_.ShouldCull(p->id)) {
      map_->EraseMapPoint(p);
      current_.points[i] = nullptr;
      current_.outlier[i] = false;
      ++erased;
    }
  }
  // Forget the points local mapping culled or fused meanwhile.
  if (++judged_frames_ % 100 == 0) static_scores_.Prune();
  if (erased > 0)
    spdlog::debug("frame at {:.3f}: {} map points erased as moving by residuals", f.timestamp,
                  erased);
  return erased;
}

void Tracker::AppendMovingKeypoints(std::vector<InconsistentKeypoint>* inconsistent) const {
  const feature::Frame& f = current_.frame;
  for (size_t i = 0; i < f.moving.size(); ++i) {
    if (f.moving[i]) inconsistent->push_back({f.keypoints[i].pt, f.depth[i]});
  }
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
