// ORB-SLAM2 settings files (Mur-Artal and Tardos, T-RO 2017; the Examples/*/*.yaml of its
// repository): OpenCV "%YAML:1.0" files with flat keys such as Camera.fx, read into typed,
// validated options.
//
// Keys and whether they are required, by sensor (M = monocular, S = stereo, D = RGB-D):
//
//   Camera.fx fy cx cy          pixels                         required M S D
//   Camera.k1 k2 p1 p2          distortion (OpenCV order)      required M S D
//   Camera.k3                   distortion                     optional, default 0
//   Camera.width height         pixels                         optional, default 0 (unknown)
//   Camera.fps                  frames per second              required M S D
//   Camera.RGB                  1: RGB order, 0: BGR           required M S D
//   Camera.bf                   baseline (m) * fx (px)         required S D
//   ThDepth                     close/far threshold, baselines required S D
//   DepthMapFactor              raw depth units per metre      required D
//   ORBextractor.nFeatures scaleFactor nLevels iniThFAST minThFAST   required M S D
//   LEFT.* RIGHT.* (height, width, D, K, R, P)   stereo rectification: optional, but all twelve
//                               once one is given (the EuRoC example's pre-rectification maps)
//   Viewer.*                    accepted and ignored
//
// A key that is not required for the sensor is still read and validated when present, so one
// file can serve several sensors (ORB-SLAM2's TUM files are used for monocular and RGB-D runs).
// Any other key, a missing required key or a value of the wrong type is an InputError naming the
// key and the file; so is a value that fails Check().
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/so3.h"
#include "moslam/io/sequence.h"

namespace moslam::io {

struct OrbExtractorOptions {
  int num_features = 1000;    // ORBextractor.nFeatures: features per image over all levels (> 0)
  double scale_factor = 1.2;  // ORBextractor.scaleFactor: scale between pyramid levels (> 1)
  int num_levels = 8;         // ORBextractor.nLevels: pyramid levels (>= 1)
  int ini_th_fast = 20;       // ORBextractor.iniThFAST: FAST threshold tried first, grey levels
  int min_th_fast = 7;        // ORBextractor.minThFAST: fallback for low-contrast cells
                              // (0 < minThFAST <= iniThFAST <= 255)
  void Check() const;
};

// One camera's entry of the stereo rectification (OpenCV's stereoRectify outputs).
struct RectificationCamera {
  int width = 0;          // <SIDE>.width, pixels of the raw image
  int height = 0;         // <SIDE>.height
  std::vector<double> D;  // <SIDE>.D: distortion (4, 5, 8, 12 or 14 values)
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();        // <SIDE>.K: raw camera matrix
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();        // <SIDE>.R: rectifying rotation
  geometry::Matrix3x4d P = geometry::Matrix3x4d::Zero();  // <SIDE>.P: rectified projection
};

struct StereoRectification {
  RectificationCamera left;   // LEFT.*
  RectificationCamera right;  // RIGHT.*
};

// Plausibility bounds of OrbSlamSettings::Check (issue 31: absurd values ran silently).
inline constexpr double kMinBaselineMetres = 1e-4;
inline constexpr double kMaxBaselineMetres = 1e3;
inline constexpr double kMinDepthMapFactor = 1e-3;
inline constexpr double kMaxDepthMapFactor = 1e6;

struct OrbSlamSettings {
  camera::PinholeOptions camera;     // Camera.fx, fy, cx, cy, k1, k2, p1, p2, k3, width, height
  double fps = 30.0;                 // Camera.fps: frames per second (> 0)
  bool rgb = true;                   // Camera.RGB: colour order of colour images; ignored for grey
  double bf = 0.0;                   // Camera.bf: pixel-metres (> 0 for stereo and RGB-D); 0: none
  double th_depth = 35.0;            // ThDepth: points closer than th_depth baselines are "close"
  double depth_map_factor = 5000.0;  // DepthMapFactor: raw depth units per metre (TUM: 5000)
  OrbExtractorOptions orb;
  std::optional<StereoRectification> rectification;

  // Metres (bf / fx); 0 when bf is 0.
  double Baseline() const;
  // ORB-SLAM2's mThDepth in metres: th_depth * baseline.
  double CloseDepthMetres() const { return th_depth * Baseline(); }

  // Throws InputError naming the settings key of the first invalid value for `sensor`.
  void Check(SensorType sensor) const;
};

// Reads and checks `path` for `sensor`. All errors are InputErrors naming the file and the key.
OrbSlamSettings LoadOrbSlamSettings(const std::string& path, SensorType sensor);

// For settings without Camera.width/Camera.height: sets the image size from the first frame
// (`size`, read from `frame_path`) and runs the checks that need it (principal point inside the
// image, focal lengths against the image side, distortion invertible over the image), which
// LoadOrbSlamSettings could not. Throws InputError naming `settings_path`, the key and the frame.
// Does nothing when the settings give the size (the run checks every frame against it).
void CompleteImageSize(OrbSlamSettings* settings, const std::string& settings_path, int width,
                       int height, const std::string& frame_path);

}  // namespace moslam::io
