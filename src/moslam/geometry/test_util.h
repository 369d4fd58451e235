// Shared helpers for geometry tests: deterministic random transforms and comparisons.
#pragma once

#include <random>

#include <gtest/gtest.h>

#include "moslam/geometry/se3.h"
#include "moslam/geometry/sim3.h"

namespace moslam::geometry::test {

inline Eigen::Vector3d RandomVector(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

inline Eigen::Quaterniond RandomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Eigen::Quaterniond(n(rng), n(rng), n(rng), n(rng)).normalized();
}

inline SE3 RandomSE3(std::mt19937& rng) { return SE3(RandomRotation(rng), RandomVector(rng, 5)); }

inline Sim3 RandomSim3(std::mt19937& rng) {
  std::uniform_real_distribution<double> log_scale(-1.5, 1.5);
  return Sim3(RandomRotation(rng), RandomVector(rng, 5), std::exp(log_scale(rng)));
}

inline ::testing::AssertionResult MatricesNear(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                               double tolerance) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "size mismatch";
  }
  const double error = (a - b).cwiseAbs().maxCoeff();
  if (error <= tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "max abs difference " << error << " > " << tolerance << "\n"
         << a << "\nvs\n"
         << b;
}

}  // namespace moslam::geometry::test
