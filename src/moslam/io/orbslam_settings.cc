#include "moslam/io/orbslam_settings.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "moslam/camera/camera_check.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/util/yaml.h"

namespace moslam::io {
namespace {

// Reads the `rows` x `cols` opencv-matrix `key` (row-major data) into `m`.
template <typename Matrix>
void ReadMatrix(YamlFile& file, const std::string& key, Matrix* m) {
  const auto values = file.Required<std::vector<double>>(key);
  const auto rows = m->rows();
  const auto cols = m->cols();
  if (static_cast<Eigen::Index>(values.size()) != rows * cols) {
    ThrowInFile(file.path(), fmt::format("key '{}' must be a {}x{} matrix ({} values), got {} "
                                         "values",
                                         key, rows, cols, rows * cols, values.size()));
  }
  for (Eigen::Index k = 0; k < rows * cols; ++k) (*m)(k / cols, k % cols) = values[k];
}

RectificationCamera ReadRectificationCamera(YamlFile& file, const std::string& side) {
  RectificationCamera camera;
  camera.width = file.Required<int>(side + ".width");
  camera.height = file.Required<int>(side + ".height");
  camera.D = file.Required<std::vector<double>>(side + ".D");
  ReadMatrix(file, side + ".K", &camera.K);
  ReadMatrix(file, side + ".R", &camera.R);
  ReadMatrix(file, side + ".P", &camera.P);
  return camera;
}

bool HasRectificationKeys(const YamlFile& file) {
  for (const std::string& key : file.Keys()) {
    if (StartsWith(key, "LEFT.") || StartsWith(key, "RIGHT.")) return true;
  }
  return false;
}

// Reads `key` into *value: required when `required`, else only when present.
template <typename T>
void ReadKey(YamlFile& file, const std::string& key, bool required, T* value) {
  if (required) {
    *value = file.Required<T>(key);
  } else {
    file.Read(key, value);
  }
}

void CheckRectificationCamera(const RectificationCamera& c, const std::string& side) {
  if (c.width <= 0 || c.height <= 0) {
    ThrowInput("{}.width and {}.height must be positive, got {}x{}", side, side, c.width, c.height);
  }
  const size_t n = c.D.size();
  if (n != 4 && n != 5 && n != 8 && n != 12 && n != 14) {
    ThrowInput("{}.D must have 4, 5, 8, 12 or 14 coefficients (OpenCV), got {}", side, n);
  }
  for (double d : c.D) {
    if (!std::isfinite(d)) ThrowInput("{}.D has a non-finite coefficient", side);
  }
  if (!c.K.allFinite() || !(c.K(0, 0) > 0.0) || !(c.K(1, 1) > 0.0) ||
      !c.K.row(2).isApprox(Eigen::RowVector3d(0, 0, 1))) {
    ThrowInput("{}.K is not a camera matrix [fx 0 cx; 0 fy cy; 0 0 1] with fx, fy > 0", side);
  }
  if (!c.R.allFinite() || !(c.R * c.R.transpose()).isIdentity(1e-6) ||
      std::abs(c.R.determinant() - 1.0) > 1e-6) {
    ThrowInput("{}.R is not a rotation matrix", side);
  }
  if (!c.P.allFinite() || !(c.P(0, 0) > 0.0) || !(c.P(1, 1) > 0.0)) {
    ThrowInput("{}.P is not a projection matrix with positive focal lengths", side);
  }
}

}  // namespace

void OrbExtractorOptions::Check() const {
  if (num_features <= 0) {
    ThrowInput("ORBextractor.nFeatures must be positive, got {}", num_features);
  }
  // The upper bound keeps the level sizes meaningful; ORB-SLAM2 uses 1.2.
  if (!std::isfinite(scale_factor) || !(scale_factor > 1.0 && scale_factor <= 4.0)) {
    ThrowInput("ORBextractor.scaleFactor must be in (1, 4], got {}", scale_factor);
  }
  if (num_levels < 1 || num_levels > 32) {
    ThrowInput("ORBextractor.nLevels must be in [1, 32], got {}", num_levels);
  }
  // FAST compares grey-level differences with > threshold: 255 would never fire.
  if (ini_th_fast < 1 || ini_th_fast > 254) {
    ThrowInput("ORBextractor.iniThFAST must be in [1, 254], got {}", ini_th_fast);
  }
  if (min_th_fast < 1 || min_th_fast > ini_th_fast) {
    ThrowInput("ORBextractor.minThFAST must be in [1, iniThFAST = {}], got {}", ini_th_fast,
               min_th_fast);
  }
}

double OrbSlamSettings::Baseline() const { return camera.fx > 0.0 ? bf / camera.fx : 0.0; }

void OrbSlamSettings::Check(SensorType sensor) const {
  camera::CheckPinholeOptions(camera, "Camera.");
  if (!std::isfinite(fps) || !(fps > 0.0)) {
    ThrowInput("Camera.fps must be a positive number of frames per second, got {}", fps);
  }
  const bool needs_bf = sensor != SensorType::kMonocular;
  if (!std::isfinite(bf) || bf < 0.0 || (needs_bf && bf == 0.0)) {
    ThrowInput("Camera.bf must be a positive baseline times fx (pixel-metres){}, got {}",
               needs_bf ? "" : " or 0", bf);
  }
  // The baseline (bf / fx) of a stereo rig or of RGB-D's virtual one lies between a tenth of a
  // millimetre and a kilometre; outside, bf is a typo (1e-9 made every point "close").
  if (bf > 0.0 && (Baseline() < kMinBaselineMetres || Baseline() > kMaxBaselineMetres)) {
    ThrowInput(
        "Camera.bf = {} gives a baseline of {:g} m (bf / Camera.fx); it must lie in "
        "[{:g}, {:g}] m",
        bf, Baseline(), kMinBaselineMetres, kMaxBaselineMetres);
  }
  if (!std::isfinite(th_depth) || !(th_depth > 0.0)) {
    ThrowInput("ThDepth must be a positive number of baselines, got {}", th_depth);
  }
  if (!std::isfinite(depth_map_factor) || !(depth_map_factor > 0.0)) {
    ThrowInput("DepthMapFactor must be a positive number of raw units per metre, got {}",
               depth_map_factor);
  }
  // Depth images count metres (1) to micrometres (1e6) per unit; 1e-30 put a raw 1 at 1e30 m.
  if (depth_map_factor < kMinDepthMapFactor || depth_map_factor > kMaxDepthMapFactor) {
    ThrowInput("DepthMapFactor = {} raw units per metre lies outside [{:g}, {:g}] (TUM: 5000)",
               depth_map_factor, kMinDepthMapFactor, kMaxDepthMapFactor);
  }
  orb.Check();
  if (rectification) {
    CheckRectificationCamera(rectification->left, "LEFT");
    CheckRectificationCamera(rectification->right, "RIGHT");
    // ORB-SLAM2 tracks in the rectified images, with Camera.* as their intrinsics: the settings
    // say "Camera.fx, .fy, etc must be the same as in LEFT.P".
    const geometry::Matrix3x4d& P = rectification->left.P;
    const double tol = 1e-6 * camera.fx;
    if (std::abs(P(0, 0) - camera.fx) > tol || std::abs(P(1, 1) - camera.fy) > tol ||
        std::abs(P(0, 2) - camera.cx) > tol || std::abs(P(1, 2) - camera.cy) > tol) {
      ThrowInput(
          "LEFT.P intrinsics ({}, {}, {}, {}) differ from Camera.fx, fy, cx, cy ({}, {}, {}, "
          "{}); they must be the same",
          P(0, 0), P(1, 1), P(0, 2), P(1, 2), camera.fx, camera.fy, camera.cx, camera.cy);
    }
    if (bf > 0.0 && std::abs(-rectification->right.P(0, 3) - bf) > tol) {
      ThrowInput("RIGHT.P(0,3) = {} does not match Camera.bf = {} (expected -bf)",
                 rectification->right.P(0, 3), bf);
    }
  }
}

OrbSlamSettings LoadOrbSlamSettings(const std::string& path, SensorType sensor) {
  YamlFile file(path);
  OrbSlamSettings s;
  camera::PinholeOptions& c = s.camera;
  c.fx = file.Required<double>("Camera.fx");
  c.fy = file.Required<double>("Camera.fy");
  c.cx = file.Required<double>("Camera.cx");
  c.cy = file.Required<double>("Camera.cy");
  c.distortion.k1 = file.Required<double>("Camera.k1");
  c.distortion.k2 = file.Required<double>("Camera.k2");
  c.distortion.p1 = file.Required<double>("Camera.p1");
  c.distortion.p2 = file.Required<double>("Camera.p2");
  file.Read("Camera.k3", &c.distortion.k3);
  file.Read("Camera.width", &c.width);
  file.Read("Camera.height", &c.height);
  s.fps = file.Required<double>("Camera.fps");
  s.rgb = file.Required<bool>("Camera.RGB");

  const bool depth_sensor = sensor != SensorType::kMonocular;
  ReadKey(file, "Camera.bf", depth_sensor, &s.bf);
  ReadKey(file, "ThDepth", depth_sensor, &s.th_depth);
  ReadKey(file, "DepthMapFactor", sensor == SensorType::kRgbD, &s.depth_map_factor);

  s.orb.num_features = file.Required<int>("ORBextractor.nFeatures");
  s.orb.scale_factor = file.Required<double>("ORBextractor.scaleFactor");
  s.orb.num_levels = file.Required<int>("ORBextractor.nLevels");
  s.orb.ini_th_fast = file.Required<int>("ORBextractor.iniThFAST");
  s.orb.min_th_fast = file.Required<int>("ORBextractor.minThFAST");

  if (HasRectificationKeys(file)) {
    s.rectification = StereoRectification{ReadRectificationCamera(file, "LEFT"),
                                          ReadRectificationCamera(file, "RIGHT")};
  }
  file.IgnorePrefix("Viewer.");
  file.RejectUnread();
  try {
    s.Check(sensor);
  } catch (const InputError& e) {
    ThrowInFile(path, e.what());
  }
  return s;
}

void CompleteImageSize(OrbSlamSettings* settings, const std::string& settings_path, int width,
                       int height, const std::string& frame_path) {
  if (settings->camera.HasSize()) return;
  camera::PinholeOptions sized = settings->camera;
  sized.width = width;
  sized.height = height;
  try {
    camera::CheckPinholeOptions(sized, "Camera.");
  } catch (const InputError& e) {
    ThrowInFile(settings_path,
                fmt::format("{} (the settings give no Camera.width/Camera.height; the size {}x{} "
                            "is the first frame's, {})",
                            e.what(), width, height, Excerpt(frame_path, 200)));
  }
  settings->camera = sized;
}

}  // namespace moslam::io
