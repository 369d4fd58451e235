// Synthetic scenes for the optim tests and benchmark: a stereo camera, points in front of it,
// noisy observations with a chosen fraction of gross outliers. Header-only test support.
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/bundle_adjuster.h"
#include "moslam/optim/observation.h"

namespace moslam::optim::synthetic {

// KITTI-like: 1241x376 image, 0.54 m baseline.
inline CameraModel StereoCamera() { return {718.9, 718.9, 607.2, 185.2, 0.54 * 718.9}; }

inline Eigen::Quaterniond SmallRotation(std::mt19937& rng, double max_angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  std::uniform_real_distribution<double> u(0.0, max_angle);
  return Eigen::Quaterniond(Eigen::AngleAxisd(u(rng), axis));
}

// A pose T_cam_world near the origin looking along +z.
inline geometry::SE3 RandomPose(std::mt19937& rng, double max_translation, double max_angle) {
  std::uniform_real_distribution<double> u(-max_translation, max_translation);
  return geometry::SE3(SmallRotation(rng, max_angle), Eigen::Vector3d(u(rng), u(rng), u(rng)));
}

// T scaled away from itself by a rotation of `angle` radians and a translation of `distance`.
inline geometry::SE3 Perturb(std::mt19937& rng, const geometry::SE3& T, double distance,
                             double angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  const Eigen::Vector3d axis = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  return geometry::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis)), distance * dir) * T;
}

// A world point seen by the camera T_cam_world at depth in [z_min, z_max] inside the image.
inline Eigen::Vector3d PointInView(std::mt19937& rng, const CameraModel& camera,
                                   const geometry::SE3& T_cam_world, double z_min, double z_max) {
  std::uniform_real_distribution<double> uu(20.0, 2 * camera.cx - 20.0);
  std::uniform_real_distribution<double> vv(20.0, 2 * camera.cy - 20.0);
  std::uniform_real_distribution<double> zz(z_min, z_max);
  const double z = zz(rng);
  const Eigen::Vector3d p_c((uu(rng) - camera.cx) / camera.fx * z,
                            (vv(rng) - camera.cy) / camera.fy * z, z);
  return T_cam_world.Inverse() * p_c;
}

// The observation of p_w in T_cam_world with pixel noise sigma / sqrt(inv_sigma2) (an octave of
// scale 1.2^octave), or a gross outlier (tens of pixels off) when `outlier`.
inline Observation Observe(std::mt19937& rng, const CameraModel& camera,
                           const geometry::SE3& T_cam_world, const Eigen::Vector3d& p_w,
                           bool stereo, double sigma, bool outlier) {
  std::uniform_int_distribution<int> octave(0, 3);
  const double scale2 = std::pow(1.2, 2 * octave(rng));
  const double s = sigma * std::sqrt(scale2);
  std::normal_distribution<double> n(0.0, s);
  const Eigen::Vector3d p_c = T_cam_world * p_w;
  const double u = camera.fx * p_c.x() / p_c.z() + camera.cx;
  Observation o;
  o.inv_sigma2 = 1.0 / scale2;
  o.pixel = Eigen::Vector2d(u + n(rng), camera.fy * p_c.y() / p_c.z() + camera.cy + n(rng));
  if (stereo) o.u_right = u - camera.bf / p_c.z() + n(rng);
  if (outlier) {
    std::uniform_real_distribution<double> off(20.0, 60.0);
    std::bernoulli_distribution sign(0.5);
    o.pixel.x() += sign(rng) ? off(rng) : -off(rng);
    o.pixel.y() += sign(rng) ? off(rng) : -off(rng);
    if (stereo) o.u_right = std::max(0.0, o.pixel.x() - camera.bf / p_c.z());
  }
  return o;
}

struct PoseScene {
  CameraModel camera;
  geometry::SE3 T_true;
  std::vector<Eigen::Vector3d> points;
  std::vector<Observation> observations;
  std::vector<bool> is_outlier;
};

// mode: 0 monocular, 1 stereo, 2 mixed (every other observation stereo).
inline PoseScene MakePoseScene(std::mt19937& rng, int n, double outlier_fraction, int mode,
                               double sigma = 1.0) {
  PoseScene scene;
  scene.camera = StereoCamera();
  scene.T_true = RandomPose(rng, 1.0, 0.3);
  std::bernoulli_distribution is_outlier(outlier_fraction);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d p = PointInView(rng, scene.camera, scene.T_true, 2.0, 30.0);
    const bool stereo = mode == 1 || (mode == 2 && i % 2 == 0);
    const bool outlier = is_outlier(rng);
    scene.points.push_back(p);
    scene.observations.push_back(
        Observe(rng, scene.camera, scene.T_true, p, stereo, sigma, outlier));
    scene.is_outlier.push_back(outlier);
  }
  return scene;
}

// Keyframes along a line (0.5 m apart, looking along +z), points seen by most of them.
struct BundleScene {
  BundleProblem problem;  // perturbed initial values
  std::vector<geometry::SE3> T_true;
  std::vector<Eigen::Vector3d> points_true;
  std::vector<bool> edge_is_outlier;
};

inline BundleScene MakeBundleScene(std::mt19937& rng, int num_poses, int num_fixed, int num_points,
                                   double outlier_fraction, double stereo_fraction,
                                   double sigma = 1.0) {
  BundleScene scene;
  BundleProblem& P = scene.problem;
  P.camera = StereoCamera();
  for (int k = 0; k < num_poses; ++k) {
    const geometry::SE3 T_world_cam(SmallRotation(rng, 0.05),
                                    Eigen::Vector3d(0.1 * k, 0.02 * k, 0.5 * k));
    scene.T_true.push_back(T_world_cam.Inverse());
    const bool fixed = k < num_fixed;
    P.T_cam_world.push_back(fixed ? scene.T_true.back()
                                  : Perturb(rng, scene.T_true.back(), 0.05, 0.02));
    P.pose_fixed.push_back(fixed);
  }
  std::uniform_int_distribution<int> anchor(0, num_poses - 1);
  std::bernoulli_distribution is_outlier(outlier_fraction), is_stereo(stereo_fraction);
  std::normal_distribution<double> n(0.0, 0.05);
  for (int j = 0; j < num_points; ++j) {
    const Eigen::Vector3d p = PointInView(rng, P.camera, scene.T_true[anchor(rng)], 3.0, 25.0);
    scene.points_true.push_back(p);
    P.points_world.push_back(p + Eigen::Vector3d(n(rng), n(rng), n(rng)));
    for (int k = 0; k < num_poses; ++k) {
      const Eigen::Vector3d p_c = scene.T_true[k] * p;
      if (p_c.z() < 1.0) continue;
      const double u = P.camera.fx * p_c.x() / p_c.z() + P.camera.cx;
      const double v = P.camera.fy * p_c.y() / p_c.z() + P.camera.cy;
      if (u < 0 || v < 0 || u > 2 * P.camera.cx || v > 2 * P.camera.cy) continue;
      const bool outlier = is_outlier(rng);
      P.edges.push_back(
          {k, j, Observe(rng, P.camera, scene.T_true[k], p, is_stereo(rng), sigma, outlier)});
      scene.edge_is_outlier.push_back(outlier);
    }
  }
  return scene;
}

}  // namespace moslam::optim::synthetic
