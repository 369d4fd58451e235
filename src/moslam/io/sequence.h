// The frame list every data-set reader produces, so that the SLAM front end iterates a TUM, KITTI,
// EuRoC or plain-folder sequence the same way:
//
//   const io::Sequence seq = io::ReadDataset(path, options);  // io/dataset.h
//   for (const io::FrameEntry& frame : seq.frames) {
//     const io::FrameImages images = io::LoadFrameImages(frame, io::ColourMode::kGrey);
//     ...  // images.left, images.right (stereo), images.depth (RGB-D, metres)
//   }
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "moslam/camera/pinhole_camera.h"

namespace moslam::io {

enum class SensorType { kMonocular, kStereo, kRgbD };

// "monocular", "stereo", "rgbd".
const char* ToString(SensorType sensor);
// Accepts the names above and "mono", "rgb-d" (case-insensitive).
std::optional<SensorType> ParseSensorType(std::string_view name);

struct FrameEntry {
  int index = 0;            // position in Sequence::frames, 0-based
  double timestamp = 0.0;   // seconds on the data set's clock (TUM: the RGB image's stamp)
  std::string image_left;   // path of the left (stereo), RGB (RGB-D) or only (monocular) image
  std::string image_right;  // stereo only; empty otherwise
  std::string depth;        // RGB-D only: 16-bit depth image; empty otherwise
};

// Calibration a data set carries with its images (KITTI's calib.txt). TUM, EuRoC and image
// folders ship none that moslam reads: their calibration comes from a settings file.
struct SequenceCalibration {
  camera::PinholeOptions camera;  // the left (or only) camera; size from the first image
  double bf = 0.0;                // stereo baseline (m) times fx (px); 0 for a monocular sequence

  double baseline() const { return camera.fx > 0.0 ? bf / camera.fx : 0.0; }  // metres
};

struct Sequence {
  std::string name;  // the data-set folder's name, e.g. "rgbd_dataset_freiburg1_xyz"
  std::string root;  // the folder the sequence was read from
  SensorType sensor = SensorType::kMonocular;
  std::vector<FrameEntry> frames;  // strictly increasing timestamps, index == position
  // The trajectory file shipped with the data (TUM groundtruth.txt, KITTI poses, EuRoC
  // state_groundtruth_estimate0/data.csv), when present; parsing it is the eval module's job.
  std::optional<std::string> ground_truth_path;
  std::optional<SequenceCalibration> calibration;

  bool empty() const { return frames.empty(); }
  size_t size() const { return frames.size(); }
};

// The same sequence seen by a monocular system: right and depth images dropped.
Sequence ToMonocular(Sequence sequence);

}  // namespace moslam::io
