#include "moslam/slam/local_mapper.h"
#include "moslam/slam/camera_model.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <set>
#include <utility>

#include <spdlog/spdlog.h>

#include "moslam/optim/bundle_adjuster.h"
#include "moslam/slam/fuse.h"
#include "moslam/slam/keyframe_culling.h"
#include "moslam/slam/new_points.h"
#include "moslam/util/check.h"

namespace moslam::slam {

void AnchorGauge(const std::vector<std::shared_ptr<map::KeyFrame>>& poses, size_t num_local,
                 std::vector<bool>* pose_fixed) {
  MOSLAM_CHECK(num_local <= poses.size() && pose_fixed->size() == poses.size());
  if (num_local == 0 ||
      std::find(pose_fixed->begin(), pose_fixed->end(), true) != pose_fixed->end()) {
    return;
  }
  size_t oldest = 0;
  for (size_t i = 1; i < num_local; ++i) {
    if (poses[i]->id < poses[oldest]->id) oldest = i;
  }
  (*pose_fixed)[oldest] = true;
}

LocalMapper::LocalMapper(map::Map* map, const camera::PinholeCamera& camera, double bf,
                         const LocalMapperOptions& options)
    : map_(map), camera_(camera), model_(CameraModelFor(camera, bf)), options_(options) {}

void LocalMapper::ProcessKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe,
                                  const std::function<bool()>& more_queued) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto busy = [&] { return more_queued && more_queued(); };
  TriangulationSearch search;
  // The BoW reads only the keyframe's immutable descriptors: computed without the lock.
  KeyFrameBow bow;
  if (database_) bow = database_->ComputeBow(keyframe->frame.descriptors);
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    if (keyframe->bad()) return;  // erased while it waited in the queue
    InsertKeyFrame(keyframe);
    if (database_) {
      if (keyframe->bow.empty()) {
        keyframe->bow = std::move(bow.bow);
        keyframe->bow_features = std::move(bow.features);
      }
      database_->Add(keyframe);
    }
    CullRecentPoints(keyframe);
    NewPointsOptions new_points;
    new_points.num_neighbours = options_.monocular ? 20 : 10;
    search = PrepareTriangulationSearch(keyframe, camera_, new_points);
  }
  RunTriangulationSearch(&search, camera_);  // on a snapshot, without the lock
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    for (const auto& p : CreatePointsFromMatches(map_, search, camera_)) {
      recent_points_.push_back(p);
    }
  }
  if (!busy()) {
    std::lock_guard<std::mutex> lock(map_->mutex());
    SearchInNeighbors(map_, keyframe, camera_, options_.monocular ? 20 : 10);
  }
  abort_ba_ = false;  // a request from before this keyframe's adjustment is void (ORB-SLAM2)
  const bool adjust = !busy() && options_.local_bundle_adjustment;
  if (adjust) LocalBundleAdjustment(keyframe);
  if (options_.keyframe_culling) {
    std::lock_guard<std::mutex> lock(map_->mutex());
    CullRedundantKeyFrames(map_, keyframe, options_.close_depth);
  }
  const double ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::lock_guard<std::mutex> lock(stats_mutex_);
  step_ms_.push_back(ms);
  if (adjust) ++local_bundle_adjustments_;
}

std::vector<double> LocalMapper::StepTimes() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return step_ms_;
}

int LocalMapper::LocalBundleAdjustments() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return local_bundle_adjustments_;
}

void LocalMapper::InsertKeyFrame(const std::shared_ptr<map::KeyFrame>& keyframe) {
  // ORB-SLAM2's ProcessNewKeyFrame: points tracking matched get this keyframe's observation;
  // points the keyframe created itself (already observed) go to the recent list for culling.
  for (size_t i = 0; i < keyframe->points.size(); ++i) {
    auto& p = keyframe->points[i];
    if (!p) continue;
    if (p->bad) {
      p = nullptr;
      continue;
    }
    if (!p->IsObservedBy(keyframe->id)) {
      p->AddObservation(keyframe, i);
      p->UpdateNormalAndDepth();
      p->ComputeDistinctiveDescriptor();
    } else {
      recent_points_.push_back(p);
    }
  }
  keyframe->UpdateConnections();
}

void LocalMapper::CullRecentPoints(const std::shared_ptr<map::KeyFrame>& keyframe) {
  // ORB-SLAM2's MapPointCulling: two keyframes after its creation a point seen by at most
  // cnThObs keyframes is erased (cnThObs: 3 stereo / RGB-D, 2 monocular).
  const int max_obs_culled = options_.monocular ? 2 : 3;
  std::vector<std::weak_ptr<map::MapPoint>> kept;
  for (const auto& weak : recent_points_) {
    auto p = weak.lock();
    if (!p || p->bad) continue;
    const uint64_t age = keyframe->id - std::min(keyframe->id, p->first_keyframe_id);
    if (p->FoundRatio() < 0.25f || (age >= 2 && p->num_observations() <= max_obs_culled)) {
      map_->EraseMapPoint(p);
    } else if (age < 3) {
      kept.push_back(p);
    }
  }
  recent_points_ = std::move(kept);
}

void LocalMapper::LocalBundleAdjustment(const std::shared_ptr<map::KeyFrame>& keyframe) {
  // ORB-SLAM2's Optimizer::LocalBundleAdjustment: the keyframe and its covisible keyframes move;
  // keyframes that see the local points but are not local stay fixed.
  optim::BundleProblem problem;
  std::vector<std::shared_ptr<map::KeyFrame>> poses;
  std::vector<std::shared_ptr<map::MapPoint>> points;
  struct EdgeRef {
    size_t pose, point, index;
  };
  std::vector<EdgeRef> edges;
  uint64_t generation = 0;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    if (keyframe->bad() || map_->keyframes().size() <= 2) return;
    generation = map_->generation();
    std::map<uint64_t, size_t> pose_index;
    std::vector<std::shared_ptr<map::KeyFrame>> local = {keyframe};
    const int covisibles = options_.max_local_keyframes > 0 ? options_.max_local_keyframes : -1;
    for (const auto& kf : keyframe->BestCovisibles(covisibles)) local.push_back(kf);
    for (const auto& kf : local) {
      pose_index[kf->id] = poses.size();
      poses.push_back(kf);
      problem.pose_fixed.push_back(kf->id == 0);
    }
    const size_t num_local = local.size();
    std::set<uint64_t> point_ids;
    for (const auto& kf : local) {
      for (const auto& p : kf->points) {
        if (p && !p->bad && point_ids.insert(p->id).second) points.push_back(p);
      }
    }
    for (size_t j = 0; j < points.size(); ++j) {
      for (const auto& [kf_id, obs] : points[j]->observations()) {
        auto kf = obs.keyframe.lock();
        if (!kf || kf->bad()) continue;
        auto it = pose_index.find(kf_id);
        if (it == pose_index.end()) {
          it = pose_index.emplace(kf_id, poses.size()).first;
          poses.push_back(kf);
          problem.pose_fixed.push_back(true);
        }
        edges.push_back({it->second, j, obs.index});
      }
    }
    if (points.empty()) return;
    AnchorGauge(poses, num_local, &problem.pose_fixed);
    problem.camera = model_;
    for (const auto& kf : poses) problem.T_cam_world.push_back(kf->T_cam_world());
    for (const auto& p : points) problem.points_world.push_back(p->position);
    for (const auto& e : edges) {
      const feature::Frame& f = poses[e.pose]->frame;
      const cv::KeyPoint& kp = f.keypoints_undistorted[e.index];
      optim::BundleProblem::Edge edge;
      edge.pose = static_cast<int>(e.pose);
      edge.point = static_cast<int>(e.point);
      edge.observation.pixel = Eigen::Vector2d(kp.pt.x, kp.pt.y);
      edge.observation.u_right = f.u_right[e.index];
      edge.observation.inv_sigma2 = f.inv_level_sigma2[kp.octave];
      problem.edges.push_back(edge);
    }
    optim::WeighFarStereo({options_.far_stereo, options_.close_depth}, &problem);
  }
  last_adjustment_observations_ = edges.size();
  optim::BundleAdjusterOptions options;
  options.num_threads = options_.num_threads;
  options.stop = &abort_ba_;
  const optim::BundleResult result = optim::AdjustBundle(problem, options);

  int outliers = 0;
  for (size_t k = 0; k < edges.size(); ++k) outliers += result.edge_inlier[k] ? 0 : 1;
  const double inliers = std::max<size_t>(1, edges.size() - outliers);
  spdlog::debug(
      "local BA kf {}: {} poses ({} fixed), {} points, {} edges, {} outliers, cost {} -> {} "
      "(mean chi2 per inlier edge {:.3f} -> {:.3f})",
      keyframe->id, poses.size(),
      std::count(problem.pose_fixed.begin(), problem.pose_fixed.end(), true), points.size(),
      edges.size(), outliers, result.initial_cost, result.final_cost,
      2.0 * result.initial_cost / inliers, 2.0 * result.final_cost / inliers);

  std::lock_guard<std::mutex> lock(map_->mutex());
  if (map_->generation() != generation) {
    // A loop correction moved the map while this ran: the result is relative to the old poses.
    spdlog::debug("local BA kf {}: dropped (map corrected meanwhile)", keyframe->id);
    return;
  }
  for (size_t k = 0; k < edges.size(); ++k) {
    if (result.edge_inlier[k]) continue;
    const auto& kf = poses[edges[k].pose];
    const auto& p = points[edges[k].point];
    if (kf->bad() || p->bad || p->IndexIn(kf->id) != static_cast<int>(edges[k].index)) continue;
    if (kf->points[edges[k].index] == p) kf->points[edges[k].index] = nullptr;
    if (p->EraseObservation(kf->id)) map_->EraseMapPoint(p);
  }
  for (size_t i = 0; i < poses.size(); ++i) {
    if (!problem.pose_fixed[i] && !poses[i]->bad()) poses[i]->SetPose(result.T_cam_world[i]);
  }
  for (size_t j = 0; j < points.size(); ++j) {
    if (points[j]->bad) continue;
    points[j]->position = result.points_world[j];
    points[j]->UpdateNormalAndDepth();
  }
}

}  // namespace moslam::slam
