// Test support of the runner tests: tiny TUM-, KITTI- and synthetic-layout sequences written into
// a TempDir with cv::imwrite, and a fake tracker that reports the ground-truth pose.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "moslam/geometry/se3.h"
#include "moslam/runner/tracker.h"
#include "moslam/testing/shared_data.h"

namespace moslam::runner::test {

inline constexpr int kCols = 24, kRows = 16;

// A turning, moving camera: the fake tracker's answer and the ground truth at time t.
inline geometry::SE3 PoseAt(double t) {
  return geometry::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitY())),
                       Eigen::Vector3d(t, 0.5 * t, 0.2 * t * t));
}

inline std::string Stamp(int i) { return fmt::format("{:.6f}", 100.0 + 0.1 * i); }
inline double StampValue(int i) { return 100.0 + 0.1 * i; }

inline void WriteImage(const testing::TempDir& dir, const std::string& name, const cv::Mat& image) {
  const std::string path = dir.Write(name, "");  // creates the folders
  ASSERT_TRUE(cv::imwrite(path, image)) << path;
}

inline std::string TumLine(double t, const geometry::SE3& pose) {
  const Eigen::Vector3d& p = pose.translation();
  const Eigen::Quaterniond& q = pose.rotation();
  return fmt::format("{:.6f} {:.9f} {:.9f} {:.9f} {:.9f} {:.9f} {:.9f} {:.9f}\n", t, p.x(), p.y(),
                     p.z(), q.x(), q.y(), q.z(), q.w());
}

// TUM RGB-D layout: rgb.txt, depth.txt, rgb/<stamp>.png (8-bit grey), depth/<stamp>.png (16-bit),
// groundtruth.txt.
inline void MakeTum(const testing::TempDir& dir, int frames) {
  std::string rgb, depth, gt;
  for (int i = 0; i < frames; ++i) {
    rgb += fmt::format("{} rgb/{}.png\n", Stamp(i), Stamp(i));
    depth += fmt::format("{} depth/{}.png\n", Stamp(i), Stamp(i));
    gt += TumLine(StampValue(i), PoseAt(StampValue(i)));
    WriteImage(dir, "rgb/" + Stamp(i) + ".png", cv::Mat(kRows, kCols, CV_8UC1, cv::Scalar(40 + i)));
    WriteImage(dir, "depth/" + Stamp(i) + ".png",
               cv::Mat(kRows, kCols, CV_16UC1, cv::Scalar(5000)));
  }
  dir.Write("rgb.txt", "# timestamp filename\n" + rgb);
  dir.Write("depth.txt", "# timestamp filename\n" + depth);
  dir.Write("groundtruth.txt", "# timestamp tx ty tz qx qy qz qw\n" + gt);
}

// KITTI odometry layout: times.txt, calib.txt, image_0/ and image_1/ 000000.png ..., poses.txt.
inline void MakeKitti(const testing::TempDir& dir, int frames) {
  std::string times, poses;
  for (int i = 0; i < frames; ++i) {
    times += fmt::format("{:.6e}\n", 0.1 * i);
    const geometry::Matrix3x4d m = PoseAt(0.1 * i).Matrix3x4();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c)
        poses += fmt::format("{:.9e}{}", m(r, c), r + c == 5 ? '\n' : ' ');
    }
    const std::string name = fmt::format("{:06d}.png", i);
    WriteImage(dir, "image_0/" + name, cv::Mat(kRows, kCols, CV_8UC1, cv::Scalar(50 + i)));
    WriteImage(dir, "image_1/" + name, cv::Mat(kRows, kCols, CV_8UC1, cv::Scalar(60 + i)));
  }
  dir.Write("times.txt", times);
  dir.Write("poses.txt", poses);
  dir.Write("calib.txt",
            "P0: 20 0 11.5 0 0 20 7.5 0 0 0 1 0\nP1: 20 0 11.5 -10 0 20 7.5 0 0 0 1 0\n");
}

// Reports the ground-truth pose of every frame's stamp, state `lost` where `lost(i)` holds, a
// keyframe every second frame; records the masks it was given.
class FakeTracker : public Tracker {
 public:
  std::function<bool(int)> lost = [](int) { return false; };
  std::function<void(int)> before_track = [](int) {};
  // The pose reported for the i-th frame given, at timestamp t.
  std::function<geometry::SE3(int, double)> pose = [](int, double t) { return PoseAt(t); };
  std::vector<cv::Mat> masks;   // FrameInput::mask of each frame, as given
  std::vector<cv::Mat> images;  // FrameInput::image
  std::vector<bool> had_right, had_depth;
  bool finished = false;

  slam::FrameReport Track(const slam::FrameInput& input) override {
    const int i = static_cast<int>(masks.size());
    before_track(i);
    masks.push_back(input.mask);
    images.push_back(input.image);
    had_right.push_back(!input.right.empty());
    had_depth.push_back(!input.depth.empty());
    slam::FrameReport report;
    report.num_features = 100 + i;
    report.num_matches = 80 + i;
    report.num_inliers = 60 + i;
    report.times.extract_ms = 1.0 + i;
    report.times.total_ms = 2.0 + i;
    if (lost(i)) {
      report.state = slam::TrackingState::kLost;
      report.reason = "too few matches, said the fake";
      return report;
    }
    report.state = slam::TrackingState::kOk;
    report.new_keyframe = i % 2 == 0;
    report.T_world_cam = pose(i, input.timestamp);
    camera_.timestamps.push_back(input.timestamp);
    camera_.poses.push_back(*report.T_world_cam);
    if (report.new_keyframe) {
      keyframes_.timestamps.push_back(input.timestamp);
      keyframes_.poses.push_back(*report.T_world_cam);
    }
    return report;
  }
  void Finish() override { finished = true; }
  eval::Trajectory CameraTrajectory() const override { return camera_; }
  eval::Trajectory KeyFrameTrajectory() const override { return keyframes_; }
  slam::MapSummary Summary() const override {
    slam::MapSummary summary;
    summary.keyframes = static_cast<int>(keyframes_.size());
    summary.map_points = 7 * summary.keyframes;
    return summary;
  }

 private:
  eval::Trajectory camera_, keyframes_;
};

}  // namespace moslam::runner::test
