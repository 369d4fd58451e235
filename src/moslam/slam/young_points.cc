// The established-points check (young_points.h).
#include "moslam/slam/young_points.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>

#include "moslam/optim/cost_functions.h"
#include "moslam/slam/frame_pose.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Vector6d = geometry::Vector6d;

// The Gauss-Newton model of a group's chi-square in the left perturbation xi of a pose T:
// chi2(Exp(xi) T) ~ cost + 2 g' xi + xi' H xi.
struct Normal {
  Matrix6d H = Matrix6d::Zero();
  Vector6d g = Vector6d::Zero();
  int n = 0;
  Normal& operator+=(const Normal& o) {
    H += o.H;
    g += o.g;
    n += o.n;
    return *this;
  }
  // The model's minimizing step, H^-1 g (H damped by a millionth of its scale, so a group that
  // leaves a direction free does not divide by zero).
  Vector6d Solve() const {
    const double damping = 1e-6 * std::max(H.diagonal().maxCoeff(), 1e-12);
    return (H + damping * Matrix6d::Identity()).ldlt().solve(g);
  }
  geometry::SE3 Minimum(const geometry::SE3& T) const { return geometry::SE3::Exp(-Solve()) * T; }
};

template <int N>
void AddObservation(const optim::CameraModel& camera, const optim::Observation& obs,
                    const Eigen::Vector3d& p_cam, Normal* normal) {
  Eigen::Matrix<double, N, 1> r;
  Eigen::Matrix<double, N, 3> J_p;
  if (!optim::internal::ProjectionResidual<N>(camera, obs, std::sqrt(obs.inv_sigma2), p_cam,
                                              r.data(), &J_p)) {
    return;
  }
  // The pose optimizer's Jacobian (same perturbation).
  const auto J = optim::internal::TangentPoseJacobian<N>(J_p, p_cam);
  normal->H += J.transpose() * J;
  normal->g += J.transpose() * r;
  ++normal->n;
}

// The matches of one group, as OptimizeFramePose takes them.
struct Group {
  std::vector<size_t> indices;          // keypoint indices into the frame
  std::vector<Eigen::Vector3d> points;  // their map points
  std::vector<size_t> match;            // position in the caller's match list
  void Add(size_t k, size_t index, const Eigen::Vector3d& p) {
    indices.push_back(index);
    points.push_back(p);
    match.push_back(k);
  }
};

double AgeThreshold(std::vector<double> ages, const YoungPointOptions& options) {
  const size_t q = std::min(ages.size() - 1, static_cast<size_t>(options.age_quantile *
                                                                 static_cast<double>(ages.size())));
  std::nth_element(ages.begin(), ages.begin() + static_cast<std::ptrdiff_t>(q), ages.end());
  return options.old_fraction * ages[q];
}

double Threshold(const optim::Observation& obs) {
  return optim::Chi2Threshold(obs, optim::kChi2Mono, optim::kChi2Stereo);
}

}  // namespace

void YoungPointOptions::Check() const {
  if (min_matches < 2)
    ThrowInput("YoungPointOptions.min_matches must be >= 2 (got {})", min_matches);
  if (!(age_quantile > 0.0 && age_quantile <= 1.0)) {
    ThrowInput("YoungPointOptions.age_quantile must be in (0, 1] (got {})", age_quantile);
  }
  if (!(old_fraction > 0.0 && old_fraction <= 1.0)) {
    ThrowInput("YoungPointOptions.old_fraction must be in (0, 1] (got {})", old_fraction);
  }
  if (min_established < 6) {
    ThrowInput("YoungPointOptions.min_established must be >= 6 (got {})", min_established);
  }
  if (min_young < 3) ThrowInput("YoungPointOptions.min_young must be >= 3 (got {})", min_young);
  if (!(min_excess > 0.0) || !std::isfinite(min_excess)) {
    ThrowInput("YoungPointOptions.min_excess must be > 0 (got {})", min_excess);
  }
  if (!(excess_per_point >= 0.0) || !std::isfinite(excess_per_point)) {
    ThrowInput("YoungPointOptions.excess_per_point must be >= 0 (got {})", excess_per_point);
  }
  if (!(prior_scale > 0.0) || !std::isfinite(prior_scale)) {
    ThrowInput("YoungPointOptions.prior_scale must be > 0 (got {})", prior_scale);
  }
  if (!(prior_translation_floor > 0.0) || !std::isfinite(prior_translation_floor)) {
    ThrowInput("YoungPointOptions.prior_translation_floor must be > 0 metres (got {})",
               prior_translation_floor);
  }
  if (!(prior_rotation_floor > 0.0) || !std::isfinite(prior_rotation_floor)) {
    ThrowInput("YoungPointOptions.prior_rotation_floor must be > 0 radians (got {})",
               prior_rotation_floor);
  }
  if (prior_window < 1) {
    ThrowInput("YoungPointOptions.prior_window must be >= 1 (got {})", prior_window);
  }
}

YoungPointCheck::YoungPointCheck(const YoungPointOptions& options) : options_(options) {
  options_.Check();
}

void YoungPointCheck::RecordPrediction(const geometry::SE3& T_final,
                                       const geometry::SE3& T_predicted) {
  const Vector6d d = (T_final * T_predicted.Inverse()).Log();
  const Eigen::Vector2d squared(d.head<3>().squaredNorm(), d.tail<3>().squaredNorm());
  if (errors_.size() < static_cast<size_t>(options_.prior_window)) {
    errors_.push_back(squared);
  } else {
    errors_[next_] = squared;
    next_ = (next_ + 1) % errors_.size();
  }
}

Eigen::Vector2d YoungPointCheck::PriorSigma() const {
  Eigen::Vector2d sigma(options_.prior_translation_floor, options_.prior_rotation_floor);
  if (errors_.empty()) return sigma;
  // Per axis, robustly: a squared norm of three axes of sigma s is s^2 x chi-square(3), whose
  // median is 2.366; the median ignores the few frames where something else went wrong.
  for (int axis = 0; axis < 2; ++axis) {
    std::vector<double> squared(errors_.size());
    for (size_t i = 0; i < errors_.size(); ++i) squared[i] = errors_[i][axis];
    const auto mid = squared.begin() + static_cast<std::ptrdiff_t>(squared.size() / 2);
    std::nth_element(squared.begin(), mid, squared.end());
    sigma[axis] = std::max(sigma[axis], options_.prior_scale * std::sqrt(*mid / 2.366));
  }
  return sigma;
}

YoungPointResult YoungPointCheck::Check(const optim::CameraModel& camera,
                                        const feature::Frame& frame,
                                        const std::vector<size_t>& indices,
                                        const std::vector<Eigen::Vector3d>& points_world,
                                        const std::vector<double>& ages,
                                        const optim::PoseOptimizerResult& full,
                                        const geometry::SE3& T_predicted, int num_threads) const {
  MOSLAM_CHECK(indices.size() == points_world.size() && indices.size() == ages.size());
  MOSLAM_CHECK(full.inlier.size() == indices.size());
  YoungPointResult out;
  const size_t n = indices.size();
  if (!options_.enabled || n < static_cast<size_t>(options_.min_matches)) return out;
  const double split = AgeThreshold(ages, options_);
  const std::vector<optim::Observation> obs = FrameObservations(frame, indices);
  const geometry::SE3& T = full.T_cam_world;
  Normal established, young;
  std::vector<bool> is_young(n);
  for (size_t k = 0; k < n; ++k) {
    is_young[k] = ages[k] < split;
    out.num_young += is_young[k];
    if (!full.inlier[k]) continue;
    Normal* group = is_young[k] ? &young : &established;
    const Eigen::Vector3d p_cam = T * points_world[k];
    if (obs[k].is_stereo()) {
      AddObservation<3>(camera, obs[k], p_cam, group);
    } else {
      AddObservation<2>(camera, obs[k], p_cam, group);
    }
  }
  out.young_inliers = young.n;
  if (established.n < options_.min_established || young.n < options_.min_young) return out;
  out.checked = true;
  // The prediction as a measurement of the pose: chi2 = (d + xi)' W (d + xi).
  const Eigen::Vector2d sigma = PriorSigma();
  Normal prior;
  const Vector6d d = (T * T_predicted.Inverse()).Log();
  prior.H.diagonal() << Eigen::Vector3d::Constant(1.0 / (sigma[0] * sigma[0])),
      Eigen::Vector3d::Constant(1.0 / (sigma[1] * sigma[1]));
  prior.g = prior.H * d;
  Normal established_with_prior = established;
  established_with_prior += prior;
  const geometry::SE3 T_established = established_with_prior.Minimum(T);
  const geometry::SE3 T_young = young.Minimum(T);
  // The young points' chi-square at the established pose against at their own (each capped at
  // the outlier threshold, so that a few gross errors do not decide).
  std::vector<double> at_established(n, 0.0), at_young(n, 0.0);
  for (size_t k = 0; k < n; ++k) {
    if (!is_young[k]) continue;
    const double threshold = Threshold(obs[k]);
    at_established[k] =
        std::min(threshold, optim::ChiSquare(camera, obs[k], T_established * points_world[k]));
    at_young[k] = std::min(threshold, optim::ChiSquare(camera, obs[k], T_young * points_world[k]));
    if (full.inlier[k]) out.excess += at_established[k] - at_young[k];
  }
  out.moving = out.excess > std::max(options_.min_excess, options_.excess_per_point * young.n);
  if (!out.moving) return out;

  // Which young points follow the mover: those closer to the young group's own pose.
  out.excluded.assign(n, false);
  Group kept;
  for (size_t k = 0; k < n; ++k) {
    out.excluded[k] = is_young[k] && at_young[k] < at_established[k];
    if (!out.excluded[k]) kept.Add(k, indices[k], points_world[k]);
  }
  const optim::PoseOptimizerResult final_pose =
      OptimizeFramePose(camera, frame, kept.indices, kept.points, T_established, num_threads);
  if (final_pose.num_inliers < options_.min_established) {
    out.moving = false;  // the established points alone do not hold a pose: keep the full one
    out.excluded.clear();
    return out;
  }
  out.pose.T_cam_world = final_pose.T_cam_world;
  out.pose.num_inliers = final_pose.num_inliers;
  out.pose.final_cost = final_pose.final_cost;
  out.pose.inlier.assign(n, false);
  out.pose.chi2.resize(n);
  for (size_t k = 0; k < n; ++k) {
    const double chi2 = optim::ChiSquare(camera, obs[k], final_pose.T_cam_world * points_world[k]);
    out.pose.chi2[k] = out.excluded[k] ? std::max(chi2, ExcludedChi2(Threshold(obs[k]))) : chi2;
  }
  for (size_t m = 0; m < kept.match.size(); ++m) {
    out.pose.inlier[kept.match[m]] = final_pose.inlier[m];
  }
  return out;
}

}  // namespace moslam::slam
