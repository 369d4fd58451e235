#include "moslam/optim/sim3_optimizer.h"

#include <cmath>
#include <limits>
#include <memory>

#include <ceres/ceres.h>

#include "moslam/optim/solver_util.h"
#include "moslam/util/error.h"

namespace moslam::optim {

void Sim3OptimizerOptions::Check() const {
  if (!(chi2 > 0.0)) throw InputError("Sim3OptimizerOptions.chi2 must be > 0");
  if (iterations_first < 1) throw InputError("Sim3OptimizerOptions.iterations_first must be >= 1");
  if (iterations_second < 0) {
    throw InputError("Sim3OptimizerOptions.iterations_second must be >= 0");
  }
}

namespace {

// Residuals [image 1 (u, v); image 2 (u, v)], whitened by each keypoint's sigma. Parameters: the
// quaternion of S_12 (x, y, z, w), its translation and log-scale.
struct Sim3MatchCost {
  Sim3MatchCost(const CameraModel& camera, const Sim3Match& m) : camera_(camera), m_(m) {}

  template <typename T>
  bool Project(const Eigen::Matrix<T, 3, 1>& p, const Eigen::Vector2d& pixel, double sigma2,
               T* r) const {
    if (!(p.z() > T(1e-6))) return false;
    const T inv = T(1.0 / std::sqrt(sigma2));
    r[0] = (T(camera_.fx) * p.x() / p.z() + T(camera_.cx) - T(pixel.x())) * inv;
    r[1] = (T(camera_.fy) * p.y() / p.z() + T(camera_.cy) - T(pixel.y())) * inv;
    return true;
  }

  template <typename T>
  bool operator()(const T* q, const T* t, const T* log_s, T* r) const {
    const Eigen::Quaternion<T> rot(q[3], q[0], q[1], q[2]);
    const Eigen::Matrix<T, 3, 1> trans(t[0], t[1], t[2]);
    const T s = exp(log_s[0]);
    const Eigen::Matrix<T, 3, 1> p1 = s * (rot * m_.p2.cast<T>()) + trans;
    const Eigen::Matrix<T, 3, 1> p2 = rot.conjugate() * (m_.p1.cast<T>() - trans) / s;
    return Project(p1, m_.pixel1, m_.sigma2_1, r) && Project(p2, m_.pixel2, m_.sigma2_2, r + 2);
  }

  CameraModel camera_;
  Sim3Match m_;
};

double Chi2(const CameraModel& camera, const Sim3Match& m, const geometry::Sim3& S_12, int image) {
  const Eigen::Vector3d p = image == 1 ? S_12 * m.p2 : S_12.Inverse() * m.p1;
  if (!(p.z() > 1e-6)) return std::numeric_limits<double>::infinity();
  const Eigen::Vector2d px(camera.fx * p.x() / p.z() + camera.cx,
                           camera.fy * p.y() / p.z() + camera.cy);
  return (px - (image == 1 ? m.pixel1 : m.pixel2)).squaredNorm() /
         (image == 1 ? m.sigma2_1 : m.sigma2_2);
}

geometry::Sim3 Solve(const CameraModel& camera, const std::vector<Sim3Match>& matches,
                     const std::vector<bool>& use, const geometry::Sim3& init, bool robust,
                     double chi2, bool fix_scale, int iterations) {
  double q[4] = {init.rotation().x(), init.rotation().y(), init.rotation().z(),
                 init.rotation().w()};
  double t[3] = {init.translation().x(), init.translation().y(), init.translation().z()};
  double log_s[1] = {std::log(init.scale())};
  ceres::Problem problem;
  int n = 0;
  for (size_t k = 0; k < matches.size(); ++k) {
    if (!use[k]) continue;
    auto* cost = new ceres::AutoDiffCostFunction<Sim3MatchCost, 4, 4, 3, 1>(
        new Sim3MatchCost(camera, matches[k]));
    problem.AddResidualBlock(cost, robust ? new ceres::HuberLoss(std::sqrt(chi2)) : nullptr, q, t,
                             log_s);
    ++n;
  }
  if (n == 0) return init;
  problem.SetManifold(q, new ceres::EigenQuaternionManifold);
  if (fix_scale) problem.SetParameterBlockConstant(log_s);
  ceres::Solver::Options options = QuietSolverOptions(iterations, 1);
  options.linear_solver_type = ceres::DENSE_QR;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return geometry::Sim3(Eigen::Quaterniond(q[3], q[0], q[1], q[2]),
                        Eigen::Vector3d(t[0], t[1], t[2]), std::exp(log_s[0]));
}

}  // namespace

Sim3OptimizerResult OptimizeSim3(const CameraModel& camera, const std::vector<Sim3Match>& matches,
                                 const geometry::Sim3& S_12_init,
                                 const Sim3OptimizerOptions& options) {
  options.Check();
  CheckCamera(camera);
  Sim3OptimizerResult result;
  std::vector<bool> use(matches.size(), true);
  result.S_12 = Solve(camera, matches, use, S_12_init, true, options.chi2, options.fix_scale,
                      options.iterations_first);
  for (size_t k = 0; k < matches.size(); ++k) {
    use[k] = Chi2(camera, matches[k], result.S_12, 1) < options.chi2 &&
             Chi2(camera, matches[k], result.S_12, 2) < options.chi2;
  }
  if (options.iterations_second > 0) {
    result.S_12 = Solve(camera, matches, use, result.S_12, false, options.chi2, options.fix_scale,
                        options.iterations_second);
  }
  result.inlier.assign(matches.size(), false);
  for (size_t k = 0; k < matches.size(); ++k) {
    result.inlier[k] = use[k] && Chi2(camera, matches[k], result.S_12, 1) < options.chi2 &&
                       Chi2(camera, matches[k], result.S_12, 2) < options.chi2;
    result.num_inliers += result.inlier[k] ? 1 : 0;
  }
  return result;
}

}  // namespace moslam::optim
