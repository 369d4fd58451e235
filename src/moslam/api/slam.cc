#include "moslam/api/slam.h"

#include <cmath>
#include <filesystem>
#include <utility>

#include <fmt/format.h>

#include "moslam/api/segmenter.h"
#include "moslam/util/error.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::api {
namespace {

std::string Describe(const cv::Mat& m) {
  if (m.empty()) return "an empty image";
  return fmt::format("{}x{} with {} channel(s) of {} bit{}", m.cols, m.rows, m.channels(),
                     m.elemSize1() * 8, m.depth() == CV_32F ? " float" : "");
}

void RequireFile(const std::string& path, const char* field) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) {
    ThrowInput("SlamOptions.{}: no file '{}'", field, path);
  }
}

}  // namespace

void SlamOptions::Check() const {
  if (settings.empty()) ThrowInput("SlamOptions.settings: no settings file given");
  RequireFile(settings, "settings");
  if (!vocabulary.empty()) RequireFile(vocabulary, "vocabulary");
  if (!model_card.empty()) RequireFile(model_card, "model_card");
  if (background_nice < 0 || background_nice > 19) {
    ThrowInput("SlamOptions.background_nice: {} is not in 0..19", background_nice);
  }
}

struct Slam::Impl {
  SlamOptions options;
  io::OrbSlamSettings settings;
  std::shared_ptr<const vocab::Vocabulary> vocabulary;
  std::unique_ptr<Segmenter> segmenter;
  // Made when the image size is known: from the settings, or else the first frame's, as
  // `moslam run` completes it (io::CompleteImageSize).
  std::unique_ptr<slam::System> system;
  int frames = 0;
  double last_timestamp = -INFINITY;
  bool finished = false;

  void MakeSystem() {
    slam::SystemOptions o;
    o.sensor = options.sensor;
    o.settings = settings;
    o.deterministic = options.deterministic;
    o.vocabulary = vocabulary;
    o.background_nice = options.background_nice;
    o.Check();
    system = std::make_unique<slam::System>(o);
  }

  void CheckImage(const cv::Mat& image, const char* what) const {
    const int type = image.type();
    if (type != CV_8UC1 && type != CV_8UC3 && type != CV_8UC4) {
      ThrowInput("{}: expected 8-bit grey, BGR/RGB or BGRA/RGBA pixels, got {}", what,
                 Describe(image));
    }
    const cv::Size size(settings.camera.width, settings.camera.height);
    if (image.size() != size) {
      ThrowInput("{}: {} is not the size of the settings {} ({}x{})", what, Describe(image),
                 options.settings, size.width, size.height);
    }
  }

  // The size check, the timestamp order and the system, before a frame is tracked.
  void Begin(double timestamp, const cv::Mat& image) {
    if (finished) ThrowInput("Slam: Track after Finish() or SaveMap()");
    if (!std::isfinite(timestamp)) ThrowInput("Slam: timestamp {} is not finite", timestamp);
    if (timestamp < last_timestamp) {
      ThrowInput("Slam: timestamp {} goes back (the last frame's is {})", timestamp,
                 last_timestamp);
    }
    if (!system) {
      if (image.empty()) ThrowInput("Slam: the first frame's image is empty");
      io::CompleteImageSize(&settings, options.settings, image.cols, image.rows, "the first frame");
      MakeSystem();
    }
    CheckImage(image, "image");
  }

  cv::Mat Mask(const cv::Mat& mask, const slam::FrameInput& input, cv::Mat* computed) {
    if (!mask.empty()) {
      if (mask.type() != CV_8UC1 || mask.size() != input.image.size()) {
        ThrowInput("mask: expected 8-bit single-channel of the image's size {}x{}, got {}",
                   input.image.cols, input.image.rows, Describe(mask));
      }
      // Tracking carries the last masks into the next frames; it keeps its own copy.
      return mask.clone();
    }
    if (!segmenter) return cv::Mat();
    *computed = segmenter->Segment(input.image, input.depth).mask;
    return *computed;
  }

  Tracked Track(slam::FrameInput input, const cv::Mat& mask) {
    Tracked tracked;
    input.mask = Mask(mask, input, &tracked.mask);
    const slam::FrameReport report = system->Track(input);
    ++frames;
    last_timestamp = input.timestamp;
    tracked.state = report.state;
    tracked.reason = report.reason;
    if (report.T_world_cam) tracked.T_world_cam = report.T_world_cam->Matrix();
    tracked.num_features = report.num_features;
    tracked.num_inliers = report.num_inliers;
    tracked.new_keyframe = report.new_keyframe;
    return tracked;
  }

  void RequireSensor(Sensor wanted, const char* call) const {
    if (options.sensor != wanted) {
      ThrowInput("Slam::{}: the system was made for {} frames", call, io::ToString(options.sensor));
    }
  }
};

Slam::Slam(const SlamOptions& options) : impl_(std::make_unique<Impl>()) {
  options.Check();
  impl_->options = options;
  impl_->settings = io::LoadOrbSlamSettings(options.settings, options.sensor);
  if (!options.vocabulary.empty()) {
    impl_->vocabulary =
        std::make_shared<const vocab::Vocabulary>(vocab::Vocabulary::Load(options.vocabulary));
  }
  if (!options.model_card.empty())
    impl_->segmenter = std::make_unique<Segmenter>(options.model_card);
  if (impl_->settings.camera.HasSize()) impl_->MakeSystem();
}

Slam::~Slam() = default;

Tracked Slam::TrackMonocular(double timestamp, const cv::Mat& image, const cv::Mat& mask) {
  impl_->RequireSensor(Sensor::kMonocular, "TrackMonocular");
  impl_->Begin(timestamp, image);
  slam::FrameInput input;
  input.timestamp = timestamp;
  input.image = image;
  return impl_->Track(std::move(input), mask);
}

Tracked Slam::TrackStereo(double timestamp, const cv::Mat& left, const cv::Mat& right,
                          const cv::Mat& mask) {
  impl_->RequireSensor(Sensor::kStereo, "TrackStereo");
  impl_->Begin(timestamp, left);
  impl_->CheckImage(right, "right image");
  if (right.type() != left.type()) {
    ThrowInput("right image: {} differs from the left image's {}", Describe(right), Describe(left));
  }
  slam::FrameInput input;
  input.timestamp = timestamp;
  input.image = left;
  input.right = right;
  return impl_->Track(std::move(input), mask);
}

Tracked Slam::TrackRgbD(double timestamp, const cv::Mat& image, const cv::Mat& depth,
                        const cv::Mat& mask) {
  impl_->RequireSensor(Sensor::kRgbD, "TrackRgbD");
  impl_->Begin(timestamp, image);
  if (depth.size() != image.size()) {
    ThrowInput("depth: {} is not the image's size {}x{}", Describe(depth), image.cols, image.rows);
  }
  slam::FrameInput input;
  input.timestamp = timestamp;
  input.image = image;
  if (depth.type() == CV_16UC1) {
    // As io::LoadDepthImage converts the PNGs `moslam run` reads, to the last bit.
    depth.convertTo(input.depth, CV_32F, 1.0 / impl_->settings.depth_map_factor);
  } else if (depth.type() == CV_32FC1) {
    input.depth = depth.clone();  // tracking keeps the last depth map to carry masks with
  } else {
    ThrowInput("depth: expected 16-bit units of DepthMapFactor or 32-bit float metres, got {}",
               Describe(depth));
  }
  return impl_->Track(std::move(input), mask);
}

void Slam::Finish() {
  impl_->finished = true;
  if (impl_->system) impl_->system->Finish();
}

eval::Trajectory Slam::Trajectory() const {
  return impl_->system ? impl_->system->CameraTrajectory() : eval::Trajectory{};
}

eval::Trajectory Slam::KeyFrameTrajectory() const {
  return impl_->system ? impl_->system->KeyFrameTrajectory() : eval::Trajectory{};
}

std::vector<Eigen::Vector3d> Slam::MapPoints() const {
  return impl_->system ? impl_->system->MapPointPositions() : std::vector<Eigen::Vector3d>{};
}

slam::MapSummary Slam::Summary() const {
  return impl_->system ? impl_->system->Summary() : slam::MapSummary{};
}

void Slam::SaveMap(const std::string& path) {
  if (!impl_->system) ThrowInput("Slam::SaveMap {}: no frame was tracked, there is no map", path);
  impl_->finished = true;
  impl_->system->SaveMap(path);
}

Sensor Slam::sensor() const { return impl_->options.sensor; }
const io::OrbSlamSettings& Slam::settings() const { return impl_->settings; }
int Slam::frames() const { return impl_->frames; }

}  // namespace moslam::api
