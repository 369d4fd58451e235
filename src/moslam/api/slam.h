// The front door for programs that embed moslam (docs/RUNNING.md, "moslam inside other
// programs"): a SLAM system made from an ORB-SLAM2 settings file, a vocabulary and, optionally, a
// model card that computes each frame's movable-object mask. Frames in, pose and state out; the
// trajectory, the map points and the map file on request. It is what `moslam run` does per frame
// (same options, same conversions), without the data-set readers and output files, so that a
// program feeding the frames of a data set gets `moslam run`'s trajectory.
//
//   moslam::api::SlamOptions options;
//   options.settings = "configs/TUM1.yaml";
//   options.vocabulary = "data/vocab/moslam_orb.mvoc";
//   moslam::api::Slam slam(options);                    // InputError on bad settings/files
//   moslam::api::Tracked t = slam.TrackRgbD(stamp, bgr, depth16);
//   if (t.T_world_cam) ...;
//   slam.Finish();
//   moslam::eval::Trajectory trajectory = slam.Trajectory();
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "moslam/eval/trajectory.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/io/sequence.h"
#include "moslam/slam/system.h"

namespace moslam::api {

using Sensor = io::SensorType;
using TrackingState = slam::TrackingState;

struct SlamOptions {
  std::string settings;    // ORB-SLAM2 settings YAML (configs/*.yaml)
  std::string vocabulary;  // vocabulary file (data/vocab/moslam_orb.mvoc); empty: none (no
                           // relocalization or loop closing)
  Sensor sensor = Sensor::kRgbD;
  // A model card (configs/models/*.yaml, type segmentation or detector) whose network computes
  // the mask of every frame tracked without one; empty: only the masks passed to Track*.
  std::string model_card;
  // As `moslam run --deterministic`: mapping in the caller's thread, fixed seeds; two runs on
  // the same frames give the same trajectory.
  bool deterministic = false;
  // Nice increment of the mapping threads (slam::SystemOptions::background_nice).
  int background_nice = 0;
  // InputError naming the field or the missing file.
  void Check() const;
};

// What one Track* call returns.
struct Tracked {
  TrackingState state = TrackingState::kNotInitialized;
  std::string reason;                          // why not ok
  std::optional<Eigen::Matrix4d> T_world_cam;  // camera-to-world, when tracked
  int num_features = 0;
  int num_inliers = 0;
  bool new_keyframe = false;
  cv::Mat mask;  // the model card's mask of this frame (CV_8UC1, 255 = movable); else empty
};

class Slam {
 public:
  explicit Slam(const SlamOptions& options);
  ~Slam();  // finishes the mapping threads
  Slam(const Slam&) = delete;
  Slam& operator=(const Slam&) = delete;

  // Images: CV_8UC1 grey, or CV_8UC3/CV_8UC4 colour in the settings' Camera.RGB order (OpenCV's
  // imread gives BGR: Camera.RGB: 0). Depth: CV_16UC1 in the settings' DepthMapFactor units (as
  // the PNGs of TUM RGB-D; converted as `moslam run` converts them) or CV_32FC1 metres. Mask:
  // CV_8UC1, non-zero = movable; empty: none (or the model card's). Every image must have the
  // size the settings give (or, when they give none, the first frame's). The pixels are read
  // during the call; nothing the caller passes is kept. InputError for a wrong type, size or
  // sensor, or a timestamp that goes back.
  Tracked TrackMonocular(double timestamp, const cv::Mat& image, const cv::Mat& mask = cv::Mat());
  Tracked TrackStereo(double timestamp, const cv::Mat& left, const cv::Mat& right,
                      const cv::Mat& mask = cv::Mat());
  Tracked TrackRgbD(double timestamp, const cv::Mat& image, const cv::Mat& depth,
                    const cv::Mat& mask = cv::Mat());

  // Waits for mapping to process every keyframe and stops its threads; later Track* calls are
  // an InputError.
  void Finish();
  // Every tracked frame's pose, following later keyframe corrections (as `moslam run` writes
  // trajectory.txt) and the keyframes' poses.
  eval::Trajectory Trajectory() const;
  eval::Trajectory KeyFrameTrajectory() const;
  // The world positions of the map's points (none before the map is initialized).
  std::vector<Eigen::Vector3d> MapPoints() const;
  slam::MapSummary Summary() const;
  // Finishes, then writes the whole map (docs/MAP_FORMAT.md).
  void SaveMap(const std::string& path);

  Sensor sensor() const;
  const io::OrbSlamSettings& settings() const;
  int frames() const;  // Track* calls so far

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace moslam::api
