// Synthetic trajectories for the eval tests (header-only, test code only).
#pragma once

#include <cmath>
#include <string>

#include "moslam/eval/trajectory.h"

namespace moslam::eval::testing {

// A smooth 3D curve with turning orientation, stamped every `dt` seconds from t0.
inline Trajectory MakeCurve(size_t n, double dt = 0.1, double t0 = 100.0,
                            const std::string& name = "curve") {
  Trajectory t;
  t.name = name;
  for (size_t i = 0; i < n; ++i) {
    const double s = static_cast<double>(i) * dt;
    const Eigen::Vector3d p(std::cos(0.3 * s) * 2.0, std::sin(0.5 * s), 0.2 * s);
    const Eigen::Vector3d omega(0.05 * std::sin(s), 0.1 * s, 0.02 * std::cos(0.7 * s));
    t.timestamps.push_back(t0 + s);
    t.poses.emplace_back(geometry::ExpSO3(omega), p);
  }
  return t;
}

// `t` with every pose moved by S (T' = S * T): a trajectory in another frame.
inline Trajectory Transformed(Trajectory t, const geometry::Sim3& S) {
  t.Transform(S);
  return t;
}

inline geometry::Sim3 SomeSim3(double scale) {
  return geometry::Sim3(geometry::ExpSO3(Eigen::Vector3d(0.3, -0.2, 0.9)),
                        Eigen::Vector3d(1.0, -2.0, 0.5), scale);
}

}  // namespace moslam::eval::testing
