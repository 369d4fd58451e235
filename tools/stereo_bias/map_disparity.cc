// Disparity error of real stereo matches against depths triangulated from ground-truth poses
// (issue 29's "measure the bias first" on KITTI, where no depth ground truth exists).
//
//   stereo_map_bias MAP_FILE POSES TIMES [--min-views 4] [--min-baseline-ratio 0.1]
//
// MAP_FILE: `moslam run --dataset kitti D --save-map MAP_FILE` on a stereo sequence; POSES and
// TIMES: the sequence's KITTI poses.txt and times.txt (T_world_cam of the left camera, the first
// at identity as the map's origin). Each map point seen by at least --min-views keyframes is
// triangulated from its left-image pixels alone, at the keyframes' ground-truth poses (linear
// least squares, then Gauss-Newton on the reprojection error): the motion baseline of a car
// moving 10 m/s is tens of metres over a point's lifetime against the 0.54 m stereo baseline, so
// the motion depth is far more precise than one stereo pair's. Points whose widest motion
// baseline is under --min-baseline-ratio of their depth, or whose reprojection RMS exceeds 1 px,
// are skipped. Every stereo observation of a kept point then gives the error of its disparity,
// d_measured - bf / z_gt (level-0 px), summarised per octave and per depth as stereo_bias does
// (stereo_error.h: errors beyond two level pixels are counted as mismatches).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>
#include <Eigen/Dense>

#include "moslam/eval/trajectory_io.h"
#include "moslam/map/map.h"
#include "moslam/mapio/map_file.h"
#include "moslam/util/error.h"
#include "stereo_error.h"

namespace {

using moslam::geometry::SE3;

struct View {
  SE3 T_cam_world;
  Eigen::Vector3d centre;  // world
  Eigen::Vector2d pixel;
  double u_right = -1.0;
  int octave = 0;
};

struct Intrinsics {
  double fx, fy, cx, cy, bf;
};

// Linear triangulation (DLT over all views), then Gauss-Newton on the pixel error. Returns false
// when a view ends behind its camera.
bool Triangulate(const std::vector<View>& views, const Intrinsics& k, Eigen::Vector3d* point,
                 double* rms) {
  Eigen::MatrixXd A(2 * views.size(), 4);
  for (size_t i = 0; i < views.size(); ++i) {
    Eigen::Matrix<double, 3, 4> P;
    P.leftCols<3>() = views[i].T_cam_world.rotation().toRotationMatrix();
    P.col(3) = views[i].T_cam_world.translation();
    const double x = (views[i].pixel.x() - k.cx) / k.fx, y = (views[i].pixel.y() - k.cy) / k.fy;
    A.row(2 * i) = x * P.row(2) - P.row(0);
    A.row(2 * i + 1) = y * P.row(2) - P.row(1);
  }
  const Eigen::Vector4d h =
      Eigen::JacobiSVD<Eigen::MatrixXd>(A, Eigen::ComputeFullV).matrixV().col(3);
  if (std::abs(h(3)) < 1e-12) return false;
  Eigen::Vector3d X = h.head<3>() / h(3);
  for (int it = 0; it < 10; ++it) {
    Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
    Eigen::Vector3d g = Eigen::Vector3d::Zero();
    for (const View& v : views) {
      const Eigen::Vector3d p = v.T_cam_world * X;
      if (p.z() <= 0.1) return false;
      const Eigen::Matrix3d R = v.T_cam_world.rotation().toRotationMatrix();
      Eigen::Matrix<double, 2, 3> J;
      J << k.fx / p.z(), 0, -k.fx * p.x() / (p.z() * p.z()), 0, k.fy / p.z(),
          -k.fy * p.y() / (p.z() * p.z());
      J = J * R;
      const Eigen::Vector2d r(k.fx * p.x() / p.z() + k.cx - v.pixel.x(),
                              k.fy * p.y() / p.z() + k.cy - v.pixel.y());
      H += J.transpose() * J;
      g += J.transpose() * r;
    }
    X -= H.ldlt().solve(g);
  }
  double sum = 0.0;
  for (const View& v : views) {
    const Eigen::Vector3d p = v.T_cam_world * X;
    if (p.z() <= 0.1) return false;
    sum += (Eigen::Vector2d(k.fx * p.x() / p.z() + k.cx, k.fy * p.y() / p.z() + k.cy) - v.pixel)
               .squaredNorm();
  }
  *rms = std::sqrt(sum / static_cast<double>(views.size()));
  *point = X;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Disparity error of a stereo map against depths triangulated from ground truth"};
  std::string map_path, poses_path, times_path;
  int min_views = 4;
  double min_baseline_ratio = 0.1;
  app.add_option("map", map_path, "Map file (moslam run --save-map)")->required();
  app.add_option("poses", poses_path, "KITTI poses.txt of the sequence")->required();
  app.add_option("times", times_path, "KITTI times.txt of the sequence")->required();
  app.add_option("--min-views", min_views, "Keyframes a point must be seen by")
      ->capture_default_str();
  app.add_option("--min-baseline-ratio", min_baseline_ratio,
                 "Widest motion baseline / depth a point needs")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    moslam::map::Map map;
    const moslam::mapio::MapIdentity identity = moslam::mapio::ReadMapIdentity(map_path);
    moslam::mapio::LoadMap(map_path, identity, &map);
    const Intrinsics k{identity.camera[0], identity.camera[1], identity.camera[2],
                       identity.camera[3], identity.camera[9]};
    moslam::eval::Trajectory gt = moslam::eval::ReadKitti(poses_path);
    moslam::eval::AttachTimes(times_path, &gt);
    const auto gt_pose = [&](double t) -> const SE3* {
      const auto it = std::lower_bound(gt.timestamps.begin(), gt.timestamps.end(), t - 1e-4);
      if (it == gt.timestamps.end() || std::abs(*it - t) > 1e-4) return nullptr;
      return &gt.poses[it - gt.timestamps.begin()];
    };
    std::vector<moslam::tools::StereoSample> samples;
    int points = 0, kept = 0;
    for (const auto& [id, point] : map.points()) {
      if (point->bad) continue;
      std::vector<View> views;
      for (const auto& [kf_id, obs] : point->observations()) {
        const auto kf = obs.keyframe.lock();
        if (!kf || kf->bad()) continue;
        const SE3* T_world_cam = gt_pose(kf->frame.timestamp);
        if (T_world_cam == nullptr) continue;
        const cv::KeyPoint& kp = kf->frame.keypoints_undistorted[obs.index];
        views.push_back({T_world_cam->Inverse(), T_world_cam->translation(),
                         Eigen::Vector2d(kp.pt.x, kp.pt.y), kf->frame.u_right[obs.index],
                         kp.octave});
      }
      if (static_cast<int>(views.size()) < min_views) continue;
      ++points;
      Eigen::Vector3d X;
      double rms = 0.0;
      if (!Triangulate(views, k, &X, &rms) || rms > 1.0) continue;
      double widest = 0.0, depth = 0.0;
      for (const View& a : views) {
        depth = std::max(depth, (a.T_cam_world * X).z());
        for (const View& b : views) widest = std::max(widest, (a.centre - b.centre).norm());
      }
      if (widest < min_baseline_ratio * depth) continue;
      ++kept;
      for (const View& v : views) {
        if (v.u_right < 0.0) continue;
        moslam::tools::StereoSample sample;
        sample.octave = v.octave;
        sample.truth = k.bf / (v.T_cam_world * X).z();
        sample.estimate = v.pixel.x() - v.u_right;
        samples.push_back(sample);
      }
    }
    std::printf(
        "%d points seen by >= %d keyframes, %d triangulated and kept; %zu stereo "
        "observations\n",
        points, min_views, kept, samples.size());
    std::vector<const moslam::tools::StereoSample*> all;
    for (const auto& sample : samples) all.push_back(&sample);
    moslam::tools::PrintErrorTables(all, "Stereo observations", k.bf,
                                    {0, 5, 10, 15, 20, 30, 45, 70});
  } catch (const std::exception& e) {
    std::fprintf(stderr, "stereo_map_bias: %s\n", e.what());
    return 2;
  }
  return 0;
}
