// Synthetic keyframes for the map-level tests: an ideal pinhole camera, points with random
// descriptors projected exactly into keyframes at given poses (monocular keypoints, level 0).
#pragma once

#include <memory>
#include <random>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/feature/test_images.h"
#include "moslam/map/map.h"

namespace moslam::slam::testing {

inline camera::PinholeCamera TestCamera() { return feature::test::TestCamera(); }

struct Scene {
  std::vector<Eigen::Vector3d> points;
  cv::Mat descriptors;  // one row per point
};

inline Scene RandomScene(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-3.0, 3.0), y(-2.0, 2.0), z(5.0, 10.0);
  Scene s;
  s.descriptors = cv::Mat(n, 32, CV_8U);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < n; ++i) {
    s.points.emplace_back(x(rng), y(rng), z(rng));
    for (int b = 0; b < 32; ++b) s.descriptors.at<uint8_t>(i, b) = static_cast<uint8_t>(byte(rng));
  }
  return s;
}

// A keyframe whose keypoint i is scene point i (every point must project into the image). With
// bf > 0 every keypoint has its exact depth and right-image column (a stereo keyframe).
inline std::shared_ptr<map::KeyFrame> ObserveScene(map::Map* map, const Scene& s,
                                                   const geometry::SE3& T_cam_world,
                                                   double bf = 0.0) {
  const camera::PinholeCamera cam = TestCamera();
  feature::Frame f;
  for (size_t i = 0; i < s.points.size(); ++i) {
    const Eigen::Vector3d p = T_cam_world * s.points[i];
    cv::KeyPoint kp;
    kp.pt.x = static_cast<float>(cam.fx() * p.x() / p.z() + cam.cx());
    kp.pt.y = static_cast<float>(cam.fy() * p.y() / p.z() + cam.cy());
    kp.octave = 0;
    kp.angle = 0.0f;
    f.keypoints.push_back(kp);
  }
  f.keypoints_undistorted = f.keypoints;
  f.descriptors = s.descriptors.clone();
  f.u_right.assign(s.points.size(), -1.0f);
  f.depth.assign(s.points.size(), -1.0f);
  for (size_t i = 0; bf > 0.0 && i < s.points.size(); ++i) {
    const double z = (T_cam_world * s.points[i]).z();
    f.depth[i] = static_cast<float>(z);
    f.u_right[i] = static_cast<float>(f.keypoints[i].pt.x - bf / z);
  }
  for (int l = 0; l < 8; ++l) {
    const float sf = static_cast<float>(std::pow(1.2, l));
    f.scale_factors.push_back(sf);
    f.inv_scale_factors.push_back(1.0f / sf);
    f.level_sigma2.push_back(sf * sf);
    f.inv_level_sigma2.push_back(1.0f / (sf * sf));
  }
  f.bounds = feature::ImageBounds{0.0f, 640.0f, 0.0f, 480.0f};
  f.grid = feature::KeypointGrid(f.bounds, f.keypoints_undistorted);
  return map->CreateKeyFrame(std::move(f), T_cam_world);
}

// Creates a map point for each index in [first, last) observed by every keyframe in `kfs`.
inline void AddSharedPoints(map::Map* map, const Scene& s,
                            const std::vector<std::shared_ptr<map::KeyFrame>>& kfs, int first,
                            int last) {
  for (int i = first; i < last; ++i) {
    auto p = map->CreateMapPoint(s.points[i], kfs.front());
    for (const auto& kf : kfs) {
      kf->points[i] = p;
      p->AddObservation(kf, i);
    }
    p->ComputeDistinctiveDescriptor();
    p->UpdateNormalAndDepth();
  }
}

inline geometry::SE3 CameraAt(double x) {
  return geometry::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-x, 0.0, 0.0));
}

}  // namespace moslam::slam::testing
