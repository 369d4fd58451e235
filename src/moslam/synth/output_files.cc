#include "moslam/synth/output_files.h"

#include <filesystem>

#include <fmt/format.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::synth {
namespace {

namespace fs = std::filesystem;

void MakeDirs(const std::string& folder, const std::vector<std::string>& subdirs) {
  std::error_code ec;
  for (const std::string& d : subdirs) {
    fs::create_directories(fs::path(folder) / d, ec);
    if (ec)
      ThrowInput("synth: cannot create {}: {}", (fs::path(folder) / d).string(), ec.message());
  }
}

std::ofstream Open(const std::string& folder, const std::string& name) {
  const std::string path = (fs::path(folder) / name).string();
  std::ofstream f(path);
  if (!f) ThrowInput("synth: cannot write {}", path);
  return f;
}

std::string Header(const SequenceSpec& spec) {
  return fmt::format("# moslam synth: preset {}: {}\n", spec.info.name, spec.info.description);
}

std::string Labels(const std::string& file, const FrameData& f, int min_pixels) {
  std::string line = file;
  for (const std::string& name : VisibleClasses(f.class_id, min_pixels)) line += " " + name;
  return line + "\n";
}

}  // namespace

std::string TumStamp(double t) { return fmt::format("{:.6f}", kTumStartTime + t); }

void WriteClassesFile(const std::string& path) {
  std::ofstream f(path);
  if (!f) ThrowInput("synth: cannot write {}", path);
  for (int c = 0; c < kNumClasses; ++c) {
    f << c << " " << ClassName(c) << " " << (IsMovableClass(c) ? 1 : 0) << "\n";
  }
}

std::string SettingsYaml(const SequenceSpec& spec) {
  const auto& c = spec.camera;
  std::string s = "%YAML:1.0\n";
  s += fmt::format(
      "# moslam synth settings: preset {} ({}x{}). Exact pinhole camera, no "
      "distortion.\n",
      spec.info.name, c.width, c.height);
  s += fmt::format("Camera.fx: {:.6f}\nCamera.fy: {:.6f}\nCamera.cx: {:.6f}\nCamera.cy: {:.6f}\n",
                   c.fx, c.fy, c.cx, c.cy);
  s += "Camera.k1: 0.0\nCamera.k2: 0.0\nCamera.p1: 0.0\nCamera.p2: 0.0\nCamera.k3: 0.0\n";
  s += fmt::format("Camera.width: {}\nCamera.height: {}\n", c.width, c.height);
  s += fmt::format("Camera.fps: {:.1f}\nCamera.RGB: 1\n", spec.info.rate_hz);
  if (spec.info.stereo) {
    s += fmt::format("Camera.bf: {:.6f}\nThDepth: 35.0\n", spec.baseline_m * c.fx);
    s += "ORBextractor.nFeatures: 2000\n";
  } else {
    // Like TUM3.yaml: the Kinect's ~7.5 cm projector baseline times fx, 40 baselines "close".
    s += "Camera.bf: 40.0\nThDepth: 40.0\nDepthMapFactor: 5000.0\n";
    s += "ORBextractor.nFeatures: 1000\n";
  }
  s += "ORBextractor.scaleFactor: 1.2\nORBextractor.nLevels: 8\n";
  s += "ORBextractor.iniThFAST: 20\nORBextractor.minThFAST: 7\n";
  return s;
}

OutputWriter::OutputWriter(const std::string& folder, const SequenceSpec& spec,
                           const GeneratorOptions& options)
    : folder_(folder),
      stereo_(spec.info.stereo),
      exact_depth_(options.write_exact_depth && !spec.info.stereo),
      png_params_({cv::IMWRITE_PNG_COMPRESSION, options.png_compression}),
      label_min_pixels_(LabelMinPixels(spec.camera.width, spec.camera.height)) {
  if (stereo_) {
    MakeDirs(folder, {"image_0", "image_1", "class", "instance", "moving"});
    times_ = Open(folder, "times.txt");
    poses_ = Open(folder, "poses.txt");
    std::ofstream calib = Open(folder, "calib.txt");
    const auto& c = spec.camera;
    for (int i = 0; i < 4; ++i) {
      const double tx = (i % 2 == 1) ? -c.fx * spec.baseline_m : 0.0;
      calib << fmt::format(
          "P{}: {:.12e} 0.000000000000e+00 {:.12e} {:.12e} 0.000000000000e+00 "
          "{:.12e} {:.12e} 0.000000000000e+00 0.000000000000e+00 "
          "0.000000000000e+00 1.000000000000e+00 0.000000000000e+00\n",
          i, c.fx, c.cx, tx, c.fy, c.cy);
    }
  } else {
    MakeDirs(folder, {"rgb", "depth", "class", "instance", "moving"});
    if (exact_depth_) MakeDirs(folder, {"depth_gt"});
    rgb_ = Open(folder, "rgb.txt");
    depth_ = Open(folder, "depth.txt");
    gt_ = Open(folder, "groundtruth.txt");
    assoc_ = Open(folder, "associations.txt");
    rgb_ << "# color images\n" << Header(spec) << "# timestamp filename\n";
    depth_ << "# depth maps\n" << Header(spec) << "# timestamp filename\n";
    gt_ << "# ground truth trajectory (T_world_cam)\n"
        << Header(spec) << "# timestamp tx ty tz qx qy qz qw\n";
  }
  labels_ = Open(folder, "labels.txt");
  labels_ << fmt::format(
      "# image-level labels: <image> <classes with at least {} pixels> (background not listed)\n",
      label_min_pixels_);
  WriteClassesFile((fs::path(folder) / "classes.txt").string());
  std::ofstream settings = Open(folder, "settings.yaml");
  settings << SettingsYaml(spec);
}

void OutputWriter::WritePng(const std::string& relative, const cv::Mat& image) {
  const std::string path = (fs::path(folder_) / relative).string();
  if (!cv::imwrite(path, image, png_params_)) ThrowInput("synth: cannot write {}", path);
}

void OutputWriter::WriteFrame(const FrameData& f) {
  cv::Mat bgr;
  std::string image;
  std::string stem;
  if (stereo_) {
    stem = fmt::format("{:06d}", index_);
    image = "image_0/" + stem + ".png";
    cv::cvtColor(f.rgb, bgr, cv::COLOR_RGB2GRAY);
    WritePng(image, bgr);
    cv::Mat right;
    cv::cvtColor(f.right, right, cv::COLOR_RGB2GRAY);
    WritePng("image_1/" + stem + ".png", right);
    times_ << fmt::format("{:.6e}\n", f.timestamp);
    if (!have_first_) {
      T_world_first_ = f.T_world_cam;
      have_first_ = true;
    }
    const auto m = (T_world_first_.Inverse() * f.T_world_cam).Matrix3x4();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 4; ++c)
        poses_ << fmt::format("{:.9e}{}", m(r, c), r == 2 && c == 3 ? "\n" : " ");
    }
  } else {
    stem = TumStamp(f.timestamp);
    image = "rgb/" + stem + ".png";
    cv::cvtColor(f.rgb, bgr, cv::COLOR_RGB2BGR);
    WritePng(image, bgr);
    WritePng("depth/" + stem + ".png", f.depth);
    if (exact_depth_) {
      cv::Mat exact;
      f.depth_m.convertTo(exact, CV_16U, 5000.0);  // rounds to the nearest 0.2 mm
      WritePng("depth_gt/" + stem + ".png", exact);
    }
    rgb_ << stem << " " << image << "\n";
    depth_ << stem << " depth/" << stem << ".png\n";
    assoc_ << stem << " " << image << " " << stem << " depth/" << stem << ".png\n";
    const auto& q = f.T_world_cam.rotation();
    const auto& t = f.T_world_cam.translation();
    gt_ << fmt::format("{} {:.6f} {:.6f} {:.6f} {:.9f} {:.9f} {:.9f} {:.9f}\n", stem, t.x(), t.y(),
                       t.z(), q.x(), q.y(), q.z(), q.w());
  }
  WritePng("class/" + stem + ".png", f.class_id);
  WritePng("instance/" + stem + ".png", f.instance);
  WritePng("moving/" + stem + ".png", f.moving);
  labels_ << Labels(image, f, label_min_pixels_);
  ++index_;
}

void OutputWriter::Finish() {
  for (std::ofstream* f : {&rgb_, &depth_, &gt_, &assoc_, &labels_, &times_, &poses_}) {
    if (f->is_open()) {
      f->close();
      if (f->fail()) ThrowInput("synth: writing a list file in {} failed", folder_);
    }
  }
}

TrainingWriter::TrainingWriter(const std::string& folder, const GeneratorOptions& options,
                               int width, int height)
    : folder_(folder),
      png_params_({cv::IMWRITE_PNG_COMPRESSION, options.png_compression}),
      label_min_pixels_(LabelMinPixels(width, height)) {
  MakeDirs(folder, {"rgb", "depth", "eval_only/class", "eval_only/instance"});
  labels_ = Open(folder, "labels.txt");
  labels_ << fmt::format(
      "# image-level labels: <image> <classes with at least {} pixels> (background not listed)\n",
      label_min_pixels_);
  WriteClassesFile((fs::path(folder) / "classes.txt").string());
  std::ofstream readme = Open(folder, "eval_only/README.txt");
  readme << "Pixel labels of the training frames: for evaluating weakly supervised segmentation "
            "only, never for training it.\n";
}

void TrainingWriter::WriteFrame(const FrameData& f) {
  const std::string stem = fmt::format("{:06d}", index_++);
  cv::Mat bgr;
  cv::cvtColor(f.rgb, bgr, cv::COLOR_RGB2BGR);
  auto write = [&](const std::string& rel, const cv::Mat& m) {
    const std::string path = (fs::path(folder_) / rel).string();
    if (!cv::imwrite(path, m, png_params_)) ThrowInput("synth: cannot write {}", path);
  };
  write("rgb/" + stem + ".png", bgr);
  // The sensor's depth (Kinect noise and holes, factor 5000, as the presets' depth/): data an
  // RGB-D camera gives with every image, not a label; the CRF of self-training cues may use it.
  MOSLAM_CHECK(!f.depth.empty()) << "training frames come from an RGB-D camera";
  write("depth/" + stem + ".png", f.depth);
  write("eval_only/class/" + stem + ".png", f.class_id);
  write("eval_only/instance/" + stem + ".png", f.instance);
  labels_ << Labels("rgb/" + stem + ".png", f, label_min_pixels_);
}

void TrainingWriter::Finish() {
  labels_.close();
  if (labels_.fail()) ThrowInput("synth: writing {}/labels.txt failed", folder_);
}

}  // namespace moslam::synth
