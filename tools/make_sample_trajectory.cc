// Writes the bundled sample (data/sample/): a ground-truth camera path and an estimate of it with
// the errors a real visual odometry run shows, so the evaluator has a default input that needs
// no download. Deterministic: the same files on every machine.
//
// Ground truth: 40 s of a hand-held camera at 30 Hz moving on a rounded figure-eight about 3 m
// across while looking at the room centre, with a small bobbing motion.
// Estimate: at 25 Hz with timestamps jittered by up to 3 ms; expressed in the frame of the first
// estimated camera (as SLAM systems do); a slow yaw drift and a 2 % scale drift accumulate; white
// noise of 4 mm and 0.2 degrees is added to every pose.
//
// Usage: make_sample_trajectory OUT_DIR
#include <cmath>
#include <cstdio>
#include <random>
#include <string>

#include "moslam/geometry/se3.h"

namespace {

using moslam::geometry::ExpSO3;
using moslam::geometry::SE3;

// Camera pose T_world_cam at time t: position on the path, z axis looking at the target.
SE3 GroundTruth(double t) {
  const double w = 2.0 * M_PI / 20.0;  // one figure-eight every 20 s
  const Eigen::Vector3d position(1.5 * std::sin(w * t), 0.8 * std::sin(2 * w * t),
                                 1.4 + 0.05 * std::sin(5.3 * t));
  const Eigen::Vector3d target(0.3 * std::cos(0.3 * t), 0.2, 0.8);
  const Eigen::Vector3d z = (target - position).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();  // world z is up
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R << x, y, z;
  return SE3(R, position);
}

void WriteTum(std::FILE* f, double t, const SE3& T) {
  const Eigen::Quaterniond& q = T.rotation();
  const Eigen::Vector3d& p = T.translation();
  std::fprintf(f, "%.6f %.6f %.6f %.6f %.6f %.6f %.6f %.6f\n", t, p.x(), p.y(), p.z(), q.x(), q.y(),
               q.z(), q.w());
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s OUT_DIR\n", argv[0]);
    return 2;
  }
  const std::string dir = argv[1];
  const double t0 = 1700000000.0;  // Unix time, as TUM files carry
  std::FILE* gt = std::fopen((dir + "/groundtruth.txt").c_str(), "w");
  std::FILE* est = std::fopen((dir + "/estimate.txt").c_str(), "w");
  if (gt == nullptr || est == nullptr) {
    std::fprintf(stderr, "cannot write into %s\n", dir.c_str());
    return 1;
  }
  std::fprintf(gt, "# moslam sample ground truth (tools/make_sample_trajectory.cc)\n");
  std::fprintf(gt, "# timestamp tx ty tz qx qy qz qw\n");
  for (int i = 0; i <= 40 * 30; ++i) WriteTum(gt, t0 + i / 30.0, GroundTruth(i / 30.0));

  std::mt19937 rng(2019);
  std::uniform_real_distribution<double> jitter(-0.003, 0.003);
  std::normal_distribution<double> noise(0.0, 1.0);
  const SE3 T_cam0_world = GroundTruth(0).Inverse();
  std::fprintf(est, "# moslam sample estimate (tools/make_sample_trajectory.cc)\n");
  for (int i = 0; i <= 40 * 25; ++i) {
    const double t = i / 25.0 + jitter(rng);
    const double drift_yaw = 0.004 * t;               // radians, grows linearly
    const double scale = 1.0 + 0.02 * t / 40.0;       // 2 % by the end
    const SE3 truth = T_cam0_world * GroundTruth(t);  // in the first camera's frame
    const SE3 drift(ExpSO3(Eigen::Vector3d(0, drift_yaw, 0)), Eigen::Vector3d::Zero());
    SE3 pose = drift * truth;
    const Eigen::Vector3d dp(noise(rng), noise(rng), noise(rng));
    const Eigen::Vector3d dr(noise(rng), noise(rng), noise(rng));
    pose = SE3(ExpSO3(dr * (0.2 * M_PI / 180.0)) * pose.rotation(),
               scale * pose.translation() + 0.004 * dp);
    WriteTum(est, t0 + t, pose);
  }
  std::fclose(gt);
  std::fclose(est);
  return 0;
}
