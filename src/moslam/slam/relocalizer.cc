#include "moslam/slam/relocalizer.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/feature/matcher.h"
#include "moslam/slam/frame_pose.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void RelocalizerOptions::Check() const {
  if (min_bow_matches < 4) throw InputError("RelocalizerOptions.min_bow_matches must be >= 4");
  if (min_optimized_inliers < 3) {
    throw InputError("RelocalizerOptions.min_optimized_inliers must be >= 3");
  }
  if (min_inliers < min_optimized_inliers) {
    throw InputError("RelocalizerOptions.min_inliers must be >= min_optimized_inliers");
  }
  if (!(wide_radius > 0.0f) || !(narrow_radius > 0.0f)) {
    throw InputError("RelocalizerOptions.wide_radius / narrow_radius must be > 0");
  }
  bow.Check();
  pnp.Check();
}

int SearchKeyFrameByProjection(const map::KeyFrame& keyframe, const feature::Frame& frame,
                               const geometry::SE3& T_cam_world, const optim::CameraModel& camera,
                               float radius, int max_distance,
                               std::vector<std::shared_ptr<map::MapPoint>>* points) {
  MOSLAM_CHECK(points->size() == frame.size());
  std::unordered_set<const map::MapPoint*> found;
  for (const auto& p : *points) {
    if (p) found.insert(p.get());
  }
  const Eigen::Vector3d center = T_cam_world.Inverse().translation();
  const float log_scale = frame.num_levels() > 1 ? std::log(frame.scale_factors[1]) : 1.0f;
  std::vector<float> angles;
  std::vector<size_t> matched;
  for (size_t k = 0; k < keyframe.points.size(); ++k) {
    const auto& p = keyframe.points[k];
    if (!p || p->bad || p->descriptor.empty() || found.count(p.get())) continue;
    const Eigen::Vector3d pc = T_cam_world * p->position;
    if (pc.z() <= 0.0) continue;
    const float u = static_cast<float>(camera.fx * pc.x() / pc.z() + camera.cx);
    const float v = static_cast<float>(camera.fy * pc.y() / pc.z() + camera.cy);
    const auto& b = frame.bounds;
    if (u < b.min_x || u > b.max_x || v < b.min_y || v > b.max_y) continue;
    const float dist = static_cast<float>((p->position - center).norm());
    if (dist < 0.8f * p->min_distance || dist > 1.2f * p->max_distance) continue;
    const int level = p->PredictScale(dist, log_scale, frame.num_levels());
    const float r = radius * frame.scale_factors[level];
    int best = 256, best_index = -1;
    for (size_t j : frame.FeaturesInArea(u, v, r, level - 1, level + 1)) {
      if ((*points)[j]) continue;
      const int d = feature::DescriptorDistance(p->descriptor.ptr<uint8_t>(), frame.descriptor(j));
      if (d < best) {
        best = d;
        best_index = static_cast<int>(j);
      }
    }
    if (best_index < 0 || best > max_distance) continue;
    (*points)[best_index] = p;
    angles.push_back(keyframe.frame.keypoints_undistorted[k].angle -
                     frame.keypoints_undistorted[best_index].angle);
    matched.push_back(static_cast<size_t>(best_index));
  }
  const std::vector<bool> keep = feature::RotationConsistent(angles);
  int n = 0;
  for (size_t m = 0; m < matched.size(); ++m) {
    if (keep[m]) {
      ++n;
    } else {
      (*points)[matched[m]] = nullptr;
    }
  }
  return n;
}

namespace {

// Pose-only optimization of the frame against `points`; outliers are cleared when `drop` is set
// (ORB-SLAM2 keeps them flagged between the two projection searches so they are not re-matched,
// and drops them at the end). Returns the inliers.
int Optimize(const feature::Frame& frame, const optim::CameraModel& camera, int num_threads,
             bool drop, geometry::SE3* T_cam_world,
             std::vector<std::shared_ptr<map::MapPoint>>* points, std::vector<bool>* outlier) {
  std::vector<size_t> index;
  std::vector<Eigen::Vector3d> positions;
  for (size_t i = 0; i < points->size(); ++i) {
    if (!(*points)[i]) continue;
    index.push_back(i);
    positions.push_back((*points)[i]->position);
  }
  const optim::PoseOptimizerResult r =
      OptimizeFramePose(camera, frame, index, positions, *T_cam_world, num_threads);
  outlier->assign(points->size(), false);
  if (r.num_inliers < 3) return 0;
  *T_cam_world = r.T_cam_world;
  for (size_t k = 0; k < index.size(); ++k) {
    if (r.inlier[k]) continue;
    (*outlier)[index[k]] = true;
    if (drop) (*points)[index[k]] = nullptr;
  }
  return r.num_inliers;
}

// One candidate keyframe, ORB-SLAM2's loop body. Fills `result` on success.
bool TryCandidate(const map::KeyFrame& keyframe, const feature::Frame& frame,
                  const KeyFrameBow& frame_bow, const optim::CameraModel& camera,
                  const RelocalizerOptions& options, RelocalizationResult* result) {
  std::vector<std::shared_ptr<map::MapPoint>> points =
      SearchByBoW(keyframe, frame, frame_bow.features, options.bow);
  if (CountMatches(points) < options.min_bow_matches) return false;
  std::vector<size_t> index;
  std::vector<Eigen::Vector3d> world;
  std::vector<Eigen::Vector2d> pixels;
  std::vector<float> sigma2;
  for (size_t i = 0; i < points.size(); ++i) {
    if (!points[i]) continue;
    const cv::KeyPoint& kp = frame.keypoints_undistorted[i];
    index.push_back(i);
    world.push_back(points[i]->position);
    pixels.emplace_back(kp.pt.x, kp.pt.y);
    sigma2.push_back(frame.level_sigma2[kp.octave]);
  }
  const PnpRansacResult pnp = SolvePnpRansac(world, pixels, sigma2, camera, options.pnp);
  if (!pnp.success) return false;
  for (size_t k = 0; k < index.size(); ++k) {
    if (!pnp.inlier[k]) points[index[k]] = nullptr;
  }
  geometry::SE3 T = pnp.T_cam_world;
  std::vector<bool> outlier;
  int good = Optimize(frame, camera, options.num_threads, true, &T, &points, &outlier);
  if (good < options.min_optimized_inliers) return false;
  if (good < options.min_inliers) {
    const int more = SearchKeyFrameByProjection(keyframe, frame, T, camera, options.wide_radius,
                                                options.wide_max_distance, &points);
    if (good + more >= options.min_inliers) {
      good = Optimize(frame, camera, options.num_threads, false, &T, &points, &outlier);
      // Many inliers but not enough: search again in a narrower window around the better pose.
      if (good > 30 && good < options.min_inliers) {
        const int narrow =
            SearchKeyFrameByProjection(keyframe, frame, T, camera, options.narrow_radius,
                                       options.narrow_max_distance, &points);
        if (good + narrow >= options.min_inliers) {
          good = Optimize(frame, camera, options.num_threads, false, &T, &points, &outlier);
        }
      }
      for (size_t i = 0; i < points.size(); ++i) {
        if (outlier[i]) points[i] = nullptr;
      }
    }
  }
  if (good < options.min_inliers) return false;
  result->success = true;
  result->T_cam_world = T;
  result->points = std::move(points);
  result->num_inliers = good;
  return true;
}

}  // namespace

RelocalizationResult Relocalize(const KeyFrameDatabase& database, const feature::Frame& frame,
                                const KeyFrameBow& frame_bow, const optim::CameraModel& camera,
                                const RelocalizerOptions& options,
                                const std::optional<RelocalizationPrior>& prior) {
  options.Check();
  MOSLAM_CHECK(!prior || prior->radius >= 0.0);
  RelocalizationResult result;
  const auto candidates = database.DetectRelocalizationCandidates(frame_bow.bow);
  result.num_candidates = static_cast<int>(candidates.size());
  for (const auto& kf : candidates) {
    if (kf->bad()) continue;
    RelocalizationResult found;
    if (!TryCandidate(*kf, frame, frame_bow, camera, options, &found)) continue;
    if (prior) {
      const double d = (found.T_cam_world.Inverse().translation() - prior->camera_center).norm();
      if (d > prior->radius) {
        ++result.refused_by_prior;
        result.nearest_refused = std::min(result.nearest_refused, d);
        continue;
      }
    }
    found.keyframe = kf;
    found.num_candidates = result.num_candidates;
    found.refused_by_prior = result.refused_by_prior;
    found.nearest_refused = result.nearest_refused;
    return found;
  }
  return result;
}

}  // namespace moslam::slam
