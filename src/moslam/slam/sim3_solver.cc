#include "moslam/slam/sim3_solver.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "moslam/geometry/alignment.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void Sim3RansacOptions::Check() const {
  if (!(probability > 0.0 && probability < 1.0)) {
    throw InputError("Sim3RansacOptions.probability must be in (0, 1)");
  }
  if (min_inliers < 3) throw InputError("Sim3RansacOptions.min_inliers must be >= 3");
  if (max_iterations < 1) throw InputError("Sim3RansacOptions.max_iterations must be >= 1");
  if (!(chi2 > 0.0)) throw InputError("Sim3RansacOptions.chi2 must be > 0");
}

namespace {

// Squared pixel distance of p_cam's projection to `pixel`; +inf behind the camera.
double ReprojectionError2(const optim::CameraModel& camera, const Eigen::Vector3d& p_cam,
                          const Eigen::Vector2d& pixel) {
  if (!(p_cam.z() > 1e-6)) return std::numeric_limits<double>::infinity();
  const double u = camera.fx * p_cam.x() / p_cam.z() + camera.cx;
  const double v = camera.fy * p_cam.y() / p_cam.z() + camera.cy;
  return (Eigen::Vector2d(u, v) - pixel).squaredNorm();
}

// The closed-form similarity mapping the p2 of `indices` onto their p1.
std::optional<geometry::Sim3> Align(const std::vector<Sim3Correspondence>& c,
                                    const std::vector<size_t>& indices, bool fix_scale) {
  Eigen::Matrix3Xd source(3, indices.size()), target(3, indices.size());
  for (size_t k = 0; k < indices.size(); ++k) {
    source.col(static_cast<Eigen::Index>(k)) = c[indices[k]].p2;
    target.col(static_cast<Eigen::Index>(k)) = c[indices[k]].p1;
  }
  if (fix_scale) {
    const auto T = geometry::AlignHorn(source, target);
    if (!T) return std::nullopt;
    return geometry::Sim3(*T);
  }
  return geometry::AlignUmeyama(source, target, /*with_scale=*/true);
}

// RANSAC iterations for `probability` with inlier ratio w and minimal sets of 3 (Fischler &
// Bolles 1981), capped by max_iterations.
int NeededIterations(double probability, double w, int max_iterations) {
  const double w3 = w * w * w;
  if (w3 >= 1.0) return 1;
  if (w3 <= 0.0) return max_iterations;
  const double n = std::ceil(std::log(1.0 - probability) / std::log(1.0 - w3));
  return static_cast<int>(std::min<double>(n, max_iterations));
}

}  // namespace

int CountSim3Inliers(const optim::CameraModel& camera,
                     const std::vector<Sim3Correspondence>& correspondences,
                     const geometry::Sim3& S_12, double chi2, std::vector<bool>* inlier) {
  const geometry::Sim3 S_21 = S_12.Inverse();
  if (inlier) inlier->assign(correspondences.size(), false);
  int n = 0;
  for (size_t i = 0; i < correspondences.size(); ++i) {
    const Sim3Correspondence& c = correspondences[i];
    const double e1 = ReprojectionError2(camera, S_12 * c.p2, c.pixel1);
    const double e2 = ReprojectionError2(camera, S_21 * c.p1, c.pixel2);
    if (e1 < chi2 * c.sigma2_1 && e2 < chi2 * c.sigma2_2) {
      ++n;
      if (inlier) (*inlier)[i] = true;
    }
  }
  return n;
}

std::optional<Sim3RansacResult> SolveSim3Ransac(
    const optim::CameraModel& camera, const std::vector<Sim3Correspondence>& correspondences,
    const Sim3RansacOptions& options) {
  options.Check();
  const size_t n = correspondences.size();
  if (n < static_cast<size_t>(options.min_inliers)) return std::nullopt;
  std::mt19937_64 rng(options.seed);
  std::uniform_int_distribution<size_t> pick(0, n - 1);
  Sim3RansacResult best;
  int needed = options.max_iterations;
  int it = 0;
  for (; it < needed; ++it) {
    std::vector<size_t> sample;
    while (sample.size() < 3) {
      const size_t k = pick(rng);
      if (std::find(sample.begin(), sample.end(), k) == sample.end()) sample.push_back(k);
    }
    const auto S = Align(correspondences, sample, options.fix_scale);
    if (!S) continue;
    std::vector<bool> inlier;
    const int count = CountSim3Inliers(camera, correspondences, *S, options.chi2, &inlier);
    if (count > best.num_inliers) {
      best.S_12 = *S;
      best.inlier = std::move(inlier);
      best.num_inliers = count;
      needed = NeededIterations(options.probability, static_cast<double>(count) / n,
                                options.max_iterations);
    }
  }
  best.iterations = it;
  if (best.num_inliers < options.min_inliers) return std::nullopt;
  // Refine on all inliers; kept only when it does not lose inliers (a 3D least-squares fit can
  // be pulled by far points whose depth is noisy).
  std::vector<size_t> inliers;
  for (size_t i = 0; i < n; ++i) {
    if (best.inlier[i]) inliers.push_back(i);
  }
  if (const auto refined = Align(correspondences, inliers, options.fix_scale)) {
    std::vector<bool> flags;
    const int count = CountSim3Inliers(camera, correspondences, *refined, options.chi2, &flags);
    if (count >= best.num_inliers) {
      best.S_12 = *refined;
      best.inlier = std::move(flags);
      best.num_inliers = count;
    }
  }
  return best;
}

}  // namespace moslam::slam
