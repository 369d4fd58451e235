// `moslam dataset info`: reads a data set (and optionally a settings file) the way `moslam run`
// will, and prints what it found, so a user can check a sequence before running on it.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "commands.h"
#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"

namespace moslam::app {
namespace {

struct DatasetInfoArgs {
  std::string path;
  std::string format = "auto";
  std::string settings;
  std::string sensor;  // empty: the data set's own
  double rate_hz = 0.0;
  double max_dt = 0.02;
  std::string associations;
  bool monocular = false;
  bool check_images = false;
};

void PrintSequence(const io::Sequence& seq, io::DatasetFormat format) {
  fmt::print("data set     {}\n", seq.root);
  fmt::print("format       {}\n", io::ToString(format));
  fmt::print("sensor       {}\n", io::ToString(seq.sensor));
  fmt::print("frames       {}\n", seq.size());
  const double first = seq.frames.front().timestamp, last = seq.frames.back().timestamp;
  const double duration = last - first;
  fmt::print("time         {:.6f} .. {:.6f} s ({:.2f} s", first, last, duration);
  if (seq.size() > 1 && duration > 0) {
    fmt::print(", {:.2f} frames/s", static_cast<double>(seq.size() - 1) / duration);
  }
  fmt::print(")\n");
  fmt::print("first frame  {}\n", seq.frames.front().image_left);
  if (!seq.frames.front().image_right.empty()) {
    fmt::print("             {}\n", seq.frames.front().image_right);
  }
  if (!seq.frames.front().depth.empty()) fmt::print("             {}\n", seq.frames.front().depth);
  fmt::print("ground truth {}\n", seq.ground_truth_path.value_or("(none)"));
  if (seq.calibration) {
    const auto& c = seq.calibration->camera;
    fmt::print("calibration  fx {:.4f} fy {:.4f} cx {:.4f} cy {:.4f}, {}x{} px", c.fx, c.fy, c.cx,
               c.cy, c.width, c.height);
    if (seq.calibration->bf > 0) {
      fmt::print(", bf {:.4f} (baseline {:.4f} m)", seq.calibration->bf,
                 seq.calibration->baseline());
    }
    fmt::print("\n");
  }
}

void PrintSettings(const io::OrbSlamSettings& s, const std::string& path) {
  const auto& c = s.camera;
  fmt::print("settings     {}\n", path);
  fmt::print("  camera     fx {} fy {} cx {} cy {}, {}x{} px, {} Hz, {}\n", c.fx, c.fy, c.cx, c.cy,
             c.width, c.height, s.fps, s.rgb ? "RGB" : "BGR");
  fmt::print("  distortion k1 {} k2 {} p1 {} p2 {} k3 {}\n", c.distortion.k1, c.distortion.k2,
             c.distortion.p1, c.distortion.p2, c.distortion.k3);
  if (s.bf > 0) {
    fmt::print("  stereo     bf {} (baseline {:.4f} m), close depth {:.3f} m\n", s.bf, s.Baseline(),
               s.CloseDepthMetres());
  }
  fmt::print("  depth      factor {}\n", s.depth_map_factor);
  fmt::print("  ORB        {} features, {} levels x {}, FAST {}/{}\n", s.orb.num_features,
             s.orb.num_levels, s.orb.scale_factor, s.orb.ini_th_fast, s.orb.min_th_fast);
}

// Loads every image of the sequence; reports the first unreadable one as an InputError.
void CheckImages(const io::Sequence& seq, double depth_factor) {
  Progress progress("checking images", seq.size(), 2.0, "frames");
  cv::Size first;
  for (const io::FrameEntry& frame : seq.frames) {
    const cv::Size size =
        io::LoadFrameImages(frame, io::ColourMode::kGrey, depth_factor).left.size();
    // One camera, one size: a frame of another size would be tracked with the wrong intrinsics
    // (issue 31; `moslam run` refuses it too).
    if (first.empty()) first = size;
    if (size != first) {
      ThrowInFile(frame.image_left,
                  fmt::format("frame {} is {}x{}, but the first frame ({}) is {}x{}", frame.index,
                              size.width, size.height, seq.frames.front().image_left, first.width,
                              first.height));
    }
    progress.Update(static_cast<size_t>(frame.index) + 1);
  }
  progress.Finish();
  fmt::print("images       all {} frames readable, sizes consistent\n", seq.size());
}

void RunInfo(const DatasetInfoArgs& args) {
  io::DatasetOptions options;
  const auto format = io::ParseDatasetFormat(args.format);
  if (!format) ThrowInput("--format: unknown data-set format '{}'", args.format);
  options.format = *format;
  options.tum.max_difference = args.max_dt;
  options.tum.associations_path = args.associations;
  options.image_folder_rate_hz = args.rate_hz;
  options.monocular = args.monocular;
  options.tum.Check();
  const io::DatasetFormat detected =
      options.format == io::DatasetFormat::kAuto
          ? io::DetectDatasetFormat(args.path).value_or(io::DatasetFormat::kAuto)
          : options.format;
  const io::Sequence seq = io::ReadDataset(args.path, options);
  PrintSequence(seq, detected);

  double depth_factor = 5000.0;
  if (!args.settings.empty()) {
    io::SensorType sensor = seq.sensor;
    if (!args.sensor.empty()) {
      const auto parsed = io::ParseSensorType(args.sensor);
      if (!parsed) ThrowInput("--sensor: unknown sensor '{}'", args.sensor);
      sensor = *parsed;
    }
    const io::OrbSlamSettings settings = io::LoadOrbSlamSettings(args.settings, sensor);
    PrintSettings(settings, args.settings);
    depth_factor = settings.depth_map_factor;
  }
  if (args.check_images) {
    std::fflush(stdout);  // the summary above comes before the progress lines on stderr
    CheckImages(seq, depth_factor);
  }
}

}  // namespace

void AddDatasetCommand(CLI::App& app) {
  CLI::App* dataset = app.add_subcommand("dataset",
                                         "Inspect data sets (TUM RGB-D, KITTI, EuRoC, "
                                         "image folders)");
  dataset->require_subcommand(1);
  auto args = std::make_shared<DatasetInfoArgs>();
  CLI::App* info = dataset->add_subcommand(
      "info", "Read a data set as `moslam run` would and print frames, timing and calibration");
  info->add_option("PATH", args->path, "Data-set folder")->required();
  info->add_option("--format", args->format, "auto, tum, kitti, euroc or folder")
      ->capture_default_str();
  info->add_option("--settings", args->settings,
                   "ORB-SLAM2 settings file to load and check against the data set");
  info->add_option("--sensor", args->sensor,
                   "monocular, stereo or rgbd: which keys the settings must have (default: the "
                   "data set's sensor)");
  info->add_option("--rate", args->rate_hz, "Frames per second of an image folder (required there)")
      ->capture_default_str();
  info->add_option("--max-dt", args->max_dt,
                   "TUM: largest RGB-depth timestamp difference to associate, seconds")
      ->capture_default_str();
  info->add_option("--associations", args->associations,
                   "TUM: associations file to use instead of rgb.txt + depth.txt");
  info->add_flag("--mono", args->monocular, "Use only the left camera");
  info->add_flag("--check-images", args->check_images,
                 "Load every image and depth map and check sizes (slow on long sequences)");
  info->callback([args] { RunInfo(*args); });
}

}  // namespace moslam::app
