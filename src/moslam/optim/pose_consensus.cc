// Pose hypotheses scored by counting agreeing matches (pose_consensus.h).
#include "moslam/optim/pose_consensus.h"

#include <cmath>
#include <random>

#include "moslam/geometry/alignment.h"
#include "moslam/optim/cost_functions.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::optim {
namespace {

// The support of the observations that agree with the pose; their count in *count.
double Score(const CameraModel& camera, const geometry::SE3& T_cam_world,
             const std::vector<Eigen::Vector3d>& points_world,
             const std::vector<Observation>& observations, const std::vector<double>& support,
             double factor, std::vector<bool>* inlier, int* count = nullptr) {
  double score = 0.0;
  int n = 0;
  for (size_t i = 0; i < observations.size(); ++i) {
    const double chi2 = ChiSquare(camera, observations[i], T_cam_world * points_world[i]);
    const bool in = chi2 <= factor * Chi2Threshold(observations[i], kChi2Mono, kChi2Stereo);
    if (inlier) (*inlier)[i] = in;
    if (!in) continue;
    ++n;
    score += support.empty() ? 1.0 : support[i];
  }
  if (count) *count = n;
  return score;
}

}  // namespace

void PoseConsensusOptions::Check() const {
  if (iterations < 1)
    ThrowInput("PoseConsensusOptions.iterations must be >= 1 (got {})", iterations);
  if (!(threshold_factor > 0.0)) {
    ThrowInput("PoseConsensusOptions.threshold_factor must be > 0 (got {})", threshold_factor);
  }
  if (!(min_gain >= 1.0)) {
    ThrowInput("PoseConsensusOptions.min_gain must be >= 1 (got {})", min_gain);
  }
}

PoseConsensus FindPoseConsensus(const CameraModel& camera, const geometry::SE3& T_cam_world_pred,
                                const std::vector<Eigen::Vector3d>& points_world,
                                const std::vector<Observation>& observations,
                                const std::vector<Eigen::Vector3d>& points_cam,
                                const PoseConsensusOptions& options,
                                const std::vector<double>& support) {
  options.Check();
  const size_t n = observations.size();
  MOSLAM_CHECK(points_world.size() == n && points_cam.size() == n);
  MOSLAM_CHECK(support.empty() || support.size() == n);
  for (double s : support) MOSLAM_CHECK(s > 0.0) << "support " << s;
  PoseConsensus result;
  result.T_cam_world = T_cam_world_pred;
  result.inlier.assign(n, false);
  result.prediction_support =
      Score(camera, T_cam_world_pred, points_world, observations, support, options.threshold_factor,
            &result.inlier, &result.prediction_inliers);
  result.support = result.prediction_support;
  result.num_inliers = result.prediction_inliers;
  std::vector<size_t> with_depth;
  for (size_t i = 0; i < n; ++i) {
    if (points_cam[i].allFinite()) with_depth.push_back(i);
  }
  if (with_depth.size() < 3) return result;
  std::mt19937 rng(options.seed);
  std::uniform_int_distribution<size_t> pick(0, with_depth.size() - 1);
  geometry::SE3 best_sample;
  double best_score = -1.0;
  Eigen::Matrix3Xd source(3, 3), target(3, 3);
  for (int it = 0; it < options.iterations; ++it) {
    size_t s[3];
    s[0] = pick(rng);
    do s[1] = pick(rng);
    while (s[1] == s[0]);
    do s[2] = pick(rng);
    while (s[2] == s[0] || s[2] == s[1]);
    for (int k = 0; k < 3; ++k) {
      source.col(k) = points_world[with_depth[s[k]]];
      target.col(k) = points_cam[with_depth[s[k]]];
    }
    const std::optional<geometry::SE3> T = geometry::AlignHorn(source, target);
    if (!T) continue;
    const double score =
        Score(camera, *T, points_world, observations, support, options.threshold_factor, nullptr);
    if (score > best_score) {
      best_score = score;
      best_sample = *T;
    }
  }
  if (best_score > 0.0 && best_score >= options.min_gain * result.prediction_support) {
    result.T_cam_world = best_sample;
    result.replaced = true;
    result.support = Score(camera, best_sample, points_world, observations, support,
                           options.threshold_factor, &result.inlier, &result.num_inliers);
  }
  return result;
}

}  // namespace moslam::optim
