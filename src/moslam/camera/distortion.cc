#include "moslam/camera/distortion.h"

#include <cmath>
#include <limits>

#include <Eigen/LU>

#include "moslam/util/error.h"

namespace moslam::camera {
namespace {

// Normalized-coordinate residual at which Undistort stops: ~1e-9 px for focal lengths of 1000 px.
constexpr double kTolerance = 1e-12;
constexpr int kMaxFixedPointIterations = 30;
constexpr int kMaxNewtonIterations = 20;

double RadialFactor(const Distortion& d, double r2) {
  return 1.0 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
}

Eigen::Vector2d Tangential(const Distortion& d, const Eigen::Vector2d& p) {
  const double x = p.x();
  const double y = p.y();
  const double r2 = x * x + y * y;
  return {2.0 * d.p1 * x * y + d.p2 * (r2 + 2.0 * x * x),
          d.p1 * (r2 + 2.0 * y * y) + 2.0 * d.p2 * x * y};
}

}  // namespace

void Distortion::Check() const {
  const auto c = Coefficients();
  const char* names[] = {"k1", "k2", "p1", "p2", "k3"};
  for (int i = 0; i < 5; ++i) {
    if (!std::isfinite(c[i]))
      ThrowInput("distortion {} must be a finite number, got {}", names[i], c[i]);
  }
}

Eigen::Vector2d Distort(const Distortion& d, const Eigen::Vector2d& undistorted) {
  return undistorted * RadialFactor(d, undistorted.squaredNorm()) + Tangential(d, undistorted);
}

Eigen::Matrix2d DistortJacobian(const Distortion& d, const Eigen::Vector2d& undistorted) {
  const double x = undistorted.x();
  const double y = undistorted.y();
  const double r2 = x * x + y * y;
  const double radial = RadialFactor(d, r2);
  // d radial / d r2
  const double dradial = d.k1 + r2 * (2.0 * d.k2 + 3.0 * r2 * d.k3);
  Eigen::Matrix2d j;
  j(0, 0) = radial + 2.0 * x * x * dradial + 2.0 * d.p1 * y + 6.0 * d.p2 * x;
  j(0, 1) = 2.0 * x * y * dradial + 2.0 * d.p1 * x + 2.0 * d.p2 * y;
  j(1, 0) = 2.0 * x * y * dradial + 2.0 * d.p1 * x + 2.0 * d.p2 * y;
  j(1, 1) = radial + 2.0 * y * y * dradial + 6.0 * d.p1 * y + 2.0 * d.p2 * x;
  return j;
}

Eigen::Vector2d Undistort(const Distortion& d, const Eigen::Vector2d& distorted) {
  if (d.IsZero()) return distorted;
  Eigen::Vector2d best = distorted;
  double best_error = (Distort(d, best) - distorted).norm();
  if (best_error < kTolerance) return best;

  // OpenCV's iteration: solve x_d = x radial(x) + tangential(x) for x, freezing the terms in x.
  Eigen::Vector2d x = distorted;
  for (int i = 0; i < kMaxFixedPointIterations; ++i) {
    const double radial = RadialFactor(d, x.squaredNorm());
    if (!(radial > 0.0)) break;  // beyond the fold of the model: the iteration has no meaning
    x = (distorted - Tangential(d, x)) / radial;
    const double error = (Distort(d, x) - distorted).norm();
    if (!std::isfinite(error)) break;
    if (error < best_error) {
      best = x;
      best_error = error;
    }
    if (error < kTolerance) return best;
  }

  // Slow or failed contraction: Newton's method from the best iterate converges quadratically.
  x = best;
  for (int i = 0; i < kMaxNewtonIterations; ++i) {
    const Eigen::Matrix2d j = DistortJacobian(d, x);
    const double det = j.determinant();
    if (!(std::abs(det) > std::numeric_limits<double>::epsilon())) break;
    x -= j.inverse() * (Distort(d, x) - distorted);
    const double error = (Distort(d, x) - distorted).norm();
    if (!std::isfinite(error)) break;
    if (error < best_error) {
      best = x;
      best_error = error;
    }
    if (error < kTolerance) break;
  }
  return best;
}

}  // namespace moslam::camera
