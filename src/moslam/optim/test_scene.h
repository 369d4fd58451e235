// Test and benchmark support: deterministic synthetic cameras, poses, points and observations
// with pixel noise at the keypoint's pyramid level and gross outliers.
#pragma once

#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/bundle_adjuster.h"
#include "moslam/optim/observation.h"

namespace moslam::optim::test {

// 640x480, f = 500 px, baseline 0.1 m.
inline CameraModel TestCamera() { return CameraModel{500.0, 500.0, 320.0, 240.0, 50.0}; }
inline constexpr double kWidth = 640.0;
inline constexpr double kHeight = 480.0;
inline constexpr double kScaleFactor = 1.2;  // ORB pyramid scale between levels
inline constexpr int kLevels = 4;            // octaves used for the noise level

inline Eigen::Vector3d Project(const CameraModel& camera, const Eigen::Vector3d& p_cam) {
  const double u = camera.fx * p_cam.x() / p_cam.z() + camera.cx;
  return {u, camera.fy * p_cam.y() / p_cam.z() + camera.cy, u - camera.bf / p_cam.z()};
}

// A camera-frame point whose projection lies inside the image at depth [min_depth, max_depth].
inline Eigen::Vector3d RandomPointInView(std::mt19937& rng, const CameraModel& camera,
                                         double min_depth, double max_depth) {
  std::uniform_real_distribution<double> u(10.0, kWidth - 10.0), v(10.0, kHeight - 10.0);
  std::uniform_real_distribution<double> depth(min_depth, max_depth);
  const double z = depth(rng);
  return {(u(rng) - camera.cx) / camera.fx * z, (v(rng) - camera.cy) / camera.fy * z, z};
}

// A pose perturbation Exp([rho; phi]) with |rho| = translation (m), |phi| = angle (rad), in
// random directions.
inline geometry::SE3 RandomPerturbation(std::mt19937& rng, double translation, double angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d rho(n(rng), n(rng), n(rng)), phi(n(rng), n(rng), n(rng));
  geometry::Vector6d xi;
  xi << translation * rho.normalized(), angle * phi.normalized();
  return geometry::SE3::Exp(xi);
}

inline geometry::SE3 RandomPose(std::mt19937& rng) { return RandomPerturbation(rng, 2.0, 1.0); }

// An observation of p_cam at a random pyramid level with Gaussian pixel noise of that level's
// sigma; stereo when `stereo`.
inline Observation NoisyObservation(std::mt19937& rng, const CameraModel& camera,
                                    const Eigen::Vector3d& p_cam, bool stereo) {
  std::uniform_int_distribution<int> level(0, kLevels - 1);
  const double sigma2 = std::pow(kScaleFactor, 2 * level(rng));
  std::normal_distribution<double> noise(0.0, std::sqrt(sigma2));
  const Eigen::Vector3d ideal = Project(camera, p_cam);
  Observation observation;
  observation.pixel = {ideal.x() + noise(rng), ideal.y() + noise(rng)};
  observation.u_right = stereo ? std::max(0.0, ideal.z() + noise(rng)) : -1.0;
  observation.inv_sigma2 = 1.0 / sigma2;
  return observation;
}

// Moves an observation at least 20 px (in every measured coordinate's norm) away from its true
// value: a gross outlier, far beyond the chi-square threshold at any level used here.
inline void MakeOutlier(std::mt19937& rng, Observation* observation) {
  std::uniform_real_distribution<double> radius(20.0, 80.0), angle(0.0, 2.0 * M_PI);
  const double r = radius(rng), a = angle(rng);
  observation->pixel += Eigen::Vector2d(r * std::cos(a), r * std::sin(a));
  if (observation->is_stereo()) {
    observation->u_right = std::max(0.0, observation->u_right + r * std::cos(a));
  }
}

// Observations of random points seen from T_cam_world; `outlier_fraction` of them gross outliers
// (flagged in *is_outlier). stereo_fraction: share of stereo observations.
struct PoseScene {
  geometry::SE3 T_cam_world;
  std::vector<Eigen::Vector3d> points_world;
  std::vector<Observation> observations;
  std::vector<bool> is_outlier;
};

inline PoseScene MakePoseScene(std::mt19937& rng, const CameraModel& camera, int n,
                               double stereo_fraction, double outlier_fraction) {
  PoseScene scene;
  scene.T_cam_world = RandomPose(rng);
  const geometry::SE3 T_world_cam = scene.T_cam_world.Inverse();
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p_cam = RandomPointInView(rng, camera, 2.0, 10.0);
    scene.points_world.push_back(T_world_cam * p_cam);
    Observation observation = NoisyObservation(rng, camera, p_cam, unit(rng) < stereo_fraction);
    const bool outlier = unit(rng) < outlier_fraction;
    if (outlier) MakeOutlier(rng, &observation);
    scene.observations.push_back(observation);
    scene.is_outlier.push_back(outlier);
  }
  return scene;
}

// A bundle adjustment scene: `num_poses` cameras 0.3 m apart along the world x axis looking along
// +z (each turned by up to ~3 deg), `num_points` points 4-12 m in front; each camera observes
// each point that projects into its image with probability `visibility`. The problem starts from
// the truth perturbed (free poses by 3 cm / 1 deg, points by 10 cm per axis); the first
// `num_fixed` poses are fixed at the truth.
struct BundleScene {
  BundleProblem problem;                     // perturbed initial values
  std::vector<geometry::SE3> true_poses;     // T_cam_world
  std::vector<Eigen::Vector3d> true_points;  // world
  std::vector<bool> edge_outlier;            // per edge: made a gross outlier
};

inline BundleScene MakeBundleScene(std::mt19937& rng, int num_poses, int num_fixed, int num_points,
                                   double visibility, double stereo_fraction,
                                   double outlier_fraction) {
  BundleScene scene;
  BundleProblem& problem = scene.problem;
  problem.camera = TestCamera();
  for (int i = 0; i < num_poses; ++i) {
    const geometry::SE3 T_world_cam =
        geometry::SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.3 * i, 0.0, 0.0)) *
        RandomPerturbation(rng, 0.0, 0.05);
    scene.true_poses.push_back(T_world_cam.Inverse());
    const bool fixed = i < num_fixed;
    problem.T_cam_world.push_back(fixed ? scene.true_poses.back()
                                        : RandomPerturbation(rng, 0.02, 0.5 * M_PI / 180.0) *
                                              scene.true_poses.back());
    problem.pose_fixed.push_back(fixed);
  }
  std::uniform_real_distribution<double> x(-2.0, 2.0 + 0.3 * num_poses), y(-1.5, 1.5), z(3.0, 8.0),
      unit(0.0, 1.0);
  std::normal_distribution<double> point_noise(0.0, 0.05);
  for (int j = 0; j < num_points; ++j) {
    scene.true_points.emplace_back(x(rng), y(rng), z(rng));
    problem.points_world.push_back(scene.true_points.back() + Eigen::Vector3d(point_noise(rng),
                                                                              point_noise(rng),
                                                                              point_noise(rng)));
    for (int i = 0; i < num_poses; ++i) {
      const Eigen::Vector3d p_cam = scene.true_poses[i] * scene.true_points.back();
      const Eigen::Vector3d pixel = Project(problem.camera, p_cam);
      const bool in_image = p_cam.z() > 0.5 && pixel.x() >= 0 && pixel.x() < kWidth &&
                            pixel.y() >= 0 && pixel.y() < kHeight;
      if (!in_image || unit(rng) >= visibility) continue;
      BundleProblem::Edge edge;
      edge.pose = i;
      edge.point = j;
      edge.observation = NoisyObservation(rng, problem.camera, p_cam, unit(rng) < stereo_fraction);
      const bool outlier = unit(rng) < outlier_fraction;
      if (outlier) MakeOutlier(rng, &edge.observation);
      problem.edges.push_back(edge);
      scene.edge_outlier.push_back(outlier);
    }
  }
  return scene;
}

}  // namespace moslam::optim::test
