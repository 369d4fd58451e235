// `moslam run`: runs the SLAM system over a data set and writes trajectories, a per-frame log and
// a summary (runner/outputs.h). The loop itself is moslam::runner (RunSequence, tested with a fake
// tracker); this file maps options and adapts slam::System to runner::Tracker.
#include <atomic>
#include <charconv>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "moslam/io/camera.h"
#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/io/orbslam_settings.h"
#include "moslam/io/video.h"
#include "moslam/net/blas_core.h"
#include "moslam/runner/mask_damage.h"
#include "moslam/runner/mask_source.h"
#include "moslam/runner/outputs.h"
#include "moslam/runner/run_loop.h"
#include "moslam/runner/stop_signals.h"
#include "moslam/runner/tracker.h"
#include "moslam/semantic/mask_refine.h"
#include "moslam/sensors/kinect.h"
#include "moslam/sensors/rosbag.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"
#include "moslam/viewer/live_viewer.h"
#include "moslam/vocab/shipped_location.h"
#if MOSLAM_HAVE_SLAM
#include "moslam/slam/system.h"
#endif

namespace moslam::app {
namespace {

struct RunArgs {
  std::vector<std::string> dataset;  // FORMAT PATH
  std::string settings;
  // none | files DIR | synth-gt | onnx | detector | model
  std::vector<std::string> mask_source = {"none"};
  std::string model_card;
  std::string crf;  // empty: the card's setting
  std::string mask_missing = "error";
  std::vector<std::string> movable;
  int mask_dilate = 0;
  std::string out;
  std::string frames;
  std::string skip_frames;
  std::string vocabulary = "default";  // FILE, "default" (the shipped one) or "none"
  double rate_hz = 0.0;
  bool side_by_side = false;  // --dataset camera: stereo halves of one device's frames
  bool live = false;          // play a recorded data set as a live source (io::ReplaySource)
  std::string topics;         // --dataset rosbag: image topics, comma-separated
  size_t queue = 4;
  bool realtime = false;
  bool deterministic = false;
  int deterministic_mapping_frames = slam::SystemOptions{}.deterministic_mapping_frames;
  int local_ba_keyframes = slam::SystemOptions{}.local_ba_keyframes;
  double deterministic_mapping_ms = slam::SystemOptions{}.deterministic_mapping_ms_per_observation;
  bool monocular = false;
  bool quiet = false;
  bool no_loop_closing = false;
  std::string far_stereo = "auto";
  bool no_loop_verification = false;
  bool no_loop_word_weights = false;
  bool no_short_loss_recovery = false;
  int mapping_nice = 10;
  // Movable objects beyond the per-frame mask (slam::SystemOptions).
  bool no_movable_evidence = false;
  bool free_space_check = false;
  bool no_moving_check = false;
  bool no_static_scores = false;
  bool no_moving_regions = false;
  bool no_propagation_depth_check = false;
  bool no_completion_planes = false;
  bool no_pose_consensus = false;
  bool young_points = false;
  bool no_motion_cross_check = false;
  int mask_margin = slam::SystemOptions{}.mask_margin_px;
  int mask_propagation = slam::SystemOptions{}.mask_propagation_frames;
  int mask_completion = slam::SystemOptions{}.mask_completion_px;
  int mask_work_scale = slam::SystemOptions{}.mask_work_scale;
  std::string segment_every = "1";  // K or "auto"
  std::string mask_damage;
  // Maps that last (issue 27, docs/MAP_FORMAT.md).
  std::string save_map;
  std::string load_map;
  bool localization = false;
  bool save_keyframe_masks = false;
  // The live viewer (issue 26; src/moslam/viewer): the port given with --viewer, if given.
  std::vector<std::string> viewer;  // CLI11 gives [] or [""] for --viewer alone
  bool viewer_on = false;
  std::string viewer_host = viewer::ServerOptions{}.host;
  bool viewer_paused = false;
  int64_t viewer_pause_at = -1;  // -1: none
  bool viewer_exit = false;
};

// "a,b" as its trimmed parts; an empty part is an error naming `option`.
std::vector<std::string> SplitList(const std::string& text, const std::string& option) {
  std::vector<std::string> parts;
  size_t begin = 0;
  while (true) {
    const size_t comma = text.find(',', begin);
    const std::string part(Trim(std::string_view(text).substr(
        begin, comma == std::string::npos ? std::string::npos : comma - begin)));
    if (part.empty()) ThrowInput("{}: an empty name in '{}'", option, text);
    parts.push_back(part);
    if (comma == std::string::npos) return parts;
    begin = comma + 1;
  }
}

// --vocabulary: a file, "none", or "default" = the one shipped with the repository
// (docs/VOCABULARY.md), looked for in the working folder and above the executable
// (vocab/shipped_location.h), else none.
std::string ResolveVocabulary(const std::string& arg) {
  if (arg == "none") return "";
  if (arg != "default") {
    if (std::filesystem::is_directory(arg)) {
      ThrowInput("--vocabulary: {} is a directory, not a vocabulary file", arg);
    }
    if (!std::filesystem::is_regular_file(arg)) ThrowInput("--vocabulary: no file '{}'", arg);
    return arg;
  }
  const std::filesystem::path cwd = std::filesystem::current_path();
  const std::filesystem::path exe = vocab::CurrentExecutable();
  const std::filesystem::path found = vocab::FindShippedVocabulary(cwd, exe);
  if (!found.empty()) {
    // Relative to the working folder where it is there (the paths in summary.json stay short).
    return found == cwd / vocab::kShippedVocabulary ? std::string(vocab::kShippedVocabulary)
                                                    : found.string();
  }
  spdlog::warn(
      "no vocabulary ({} is neither in the working folder nor above {}; pass --vocabulary FILE): "
      "no relocalization or loop closing",
      vocab::kShippedVocabulary, exe.empty() ? std::string("the executable") : exe.string());
  return "";
}

#if MOSLAM_HAVE_SLAM
// slam::System behind the runner's interface; the map is saved when the run finishes (--save-map).
class SystemTracker : public runner::Tracker {
 public:
  SystemTracker(const slam::SystemOptions& options, std::string save_map)
      : system_(options), save_map_(std::move(save_map)) {}
  slam::FrameReport Track(const slam::FrameInput& input) override { return system_.Track(input); }
  void Finish() override {
    system_.Finish();
    if (!save_map_.empty()) system_.SaveMap(save_map_);
  }
  eval::Trajectory CameraTrajectory() const override { return system_.CameraTrajectory(); }
  eval::Trajectory KeyFrameTrajectory() const override { return system_.KeyFrameTrajectory(); }
  slam::MapSummary Summary() const override { return system_.Summary(); }
  bool View(slam::SystemView* view, const slam::ViewRequest& request) override {
    system_.View(view, request);
    return true;
  }
  void Watch(bool watched) override { system_.Watch(watched); }

 private:
  slam::System system_;
  std::string save_map_;
};

// --save-map / --load-map / --localization, checked before any frame is read.
void SetMapOptions(const RunArgs& args, slam::SystemOptions* options) {
  if (args.localization && args.load_map.empty()) {
    ThrowInput("--localization: needs --load-map FILE (the map to localize in)");
  }
  if (!args.save_map.empty()) {
    const auto folder = std::filesystem::path(args.save_map).parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder)) {
      ThrowInput("--save-map {}: no folder {}", args.save_map, folder.string());
    }
    if (std::filesystem::is_directory(args.save_map)) {
      ThrowInput("--save-map {}: is a directory", args.save_map);
    }
  }
  if (options->vocabulary_path.empty() && !args.load_map.empty()) {
    ThrowInput("--load-map {}: needs a vocabulary to relocalize in the map (--vocabulary)",
               args.load_map);
  }
  options->load_map = args.load_map;
  options->localization = args.localization;
}
#endif

// --segment-every: K >= 1, or "auto" (RunOptions::segment_every 0), which times decide and
// --deterministic therefore refuses.
int ParseSegmentEvery(const std::string& text, bool deterministic) {
  if (text == "auto") {
    if (deterministic) {
      ThrowInput(
          "--segment-every auto picks the frames from measured times, which --deterministic "
          "cannot repeat; give a number");
    }
    return 0;
  }
  int every = 0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), every);
  if (error != std::errc() || end != text.data() + text.size() || every < 1) {
    ThrowInput("--segment-every: expected a whole number >= 1 or auto, got '{}'", text);
  }
  return every;
}

std::unique_ptr<runner::Tracker> MakeTracker(const io::OrbSlamSettings& settings,
                                             io::SensorType sensor, const RunArgs& args) {
#if MOSLAM_HAVE_SLAM
  slam::SystemOptions options;
  options.sensor = sensor;
  options.settings = settings;
  options.deterministic = args.deterministic;
  options.deterministic_mapping_frames = args.deterministic_mapping_frames;
  options.deterministic_mapping_ms_per_observation = args.deterministic_mapping_ms;
  options.local_ba_keyframes = args.local_ba_keyframes;
  options.vocabulary_path = ResolveVocabulary(args.vocabulary);
  options.loop_closing = !args.no_loop_closing;
  if (args.far_stereo == "full") options.far_stereo = optim::FarStereo::kFull;
  if (args.far_stereo == "weighted") options.far_stereo = optim::FarStereo::kDepthWeighted;
  if (args.far_stereo == "monocular") options.far_stereo = optim::FarStereo::kMonocular;
  options.loop_verification = !args.no_loop_verification;
  options.loop_recent_word_weights = !args.no_loop_word_weights;
  options.short_loss_recovery = !args.no_short_loss_recovery;
  options.background_nice = args.mapping_nice;
  options.movable_evidence = !args.no_movable_evidence;
  options.free_space_evidence = args.free_space_check;
  options.moving_keypoint_check = !args.no_moving_check;
  options.static_scores = !args.no_static_scores;
  options.moving_regions = !args.no_moving_regions;
  options.mask_propagation_depth_check = !args.no_propagation_depth_check;
  options.completion_structure = !args.no_completion_planes;
  options.pose_consensus = !args.no_pose_consensus;
  options.young_points = args.young_points;
  options.report_keyframe_masks = args.save_keyframe_masks;
  options.motion_cross_check = !args.no_motion_cross_check;
  options.mask_margin_px = args.mask_margin;
  options.mask_propagation_frames = args.mask_propagation;
  options.mask_completion_px = args.mask_completion;
  options.mask_work_scale = args.mask_work_scale;
  SetMapOptions(args, &options);
  options.Check();
  return std::make_unique<SystemTracker>(options, args.save_map);
#else
  (void)settings;
  (void)sensor;
  (void)args;
  ThrowInput(
      "this moslam was built without the SLAM core (target moslam::slam); `moslam run` "
      "needs it");
#endif
}

runner::MaskOptions MakeMaskOptions(const RunArgs& args) {
  runner::MaskOptions options;
  const auto kind = runner::ParseMaskSourceKind(args.mask_source.at(0));
  if (!kind) {
    ThrowInput(
        "--mask-source: unknown source '{}' (none, files DIR, synth-gt, onnx, detector, model)",
        args.mask_source[0]);
  }
  options.kind = *kind;
  const bool takes_folder = *kind == runner::MaskSourceKind::kFiles;
  if (args.mask_source.size() == 2 && !takes_folder) {
    ThrowInput("--mask-source {} takes no folder (got '{}')", args.mask_source[0],
               args.mask_source[1]);
  }
  if (takes_folder && args.mask_source.size() == 2) options.folder = args.mask_source[1];
  options.missing_empty = args.mask_missing == "empty";
  options.movable = args.movable;
  options.dilate_px = args.mask_dilate;
  options.model_card = args.model_card;
  // libtorch's results depend on its thread count (runner::MaskOptions::network_threads).
  if (args.deterministic) options.network_threads = 1;
  if (!args.crf.empty()) {
    options.crf = semantic::ParseCrfMode(args.crf);
    if (!options.crf) ThrowInput("--crf: '{}' is none of none, c, d, cd", args.crf);
  }
  return options;
}

// The image size the intrinsics are for: the settings', or the first frame's when they give
// none, so that the checks that need a size (distortion invertible over the image, principal
// point inside it) still run before tracking, and every later frame must match it (issue 31).
void SetImageSize(const io::Sequence& sequence, const std::string& settings_path,
                  io::OrbSlamSettings* settings, runner::RunOptions* options) {
  std::string source = settings_path;
  if (!settings->camera.HasSize()) {
    const std::string& first = sequence.frames.front().image_left;
    const cv::Mat image = options->read_images ? options->read_images(sequence.frames.front()).left
                                               : io::LoadGreyImage(first);
    io::CompleteImageSize(settings, settings_path, image.cols, image.rows, first);
    source = fmt::format("{} (none given there: the first frame's, {})", settings_path, first);
  }
  options->image_size = cv::Size(settings->camera.width, settings->camera.height);
  options->image_size_source = source;
}

// Masks that are files named after the images (files, synth-gt) have nothing to be named after
// in a video, a bag or a camera's frames.
void RefuseFileMasks(const RunArgs& args, const std::string& what) {
  const auto kind = runner::ParseMaskSourceKind(args.mask_source.at(0));
  if (kind == runner::MaskSourceKind::kFiles || kind == runner::MaskSourceKind::kSynthGt) {
    ThrowInput(
        "--mask-source {}: needs image files named like the masks; {} has none (onnx, "
        "detector or model compute masks from the frames)",
        args.mask_source[0], what);
  }
}

// --dataset video FILE: a monocular sequence whose frames are decoded in the loader thread
// (io/video.h), stamped by the container or by --rate.
void SetUpVideo(const RunArgs& args, const std::string& path, io::Sequence* sequence,
                runner::RunOptions* options) {
  RefuseFileMasks(args, fmt::format("a video ({})", path));
  io::VideoOptions video;
  video.rate_hz = args.rate_hz;
  *sequence = io::ReadVideo(path, video);
  auto reader = std::make_shared<io::VideoReader>(path);
  options->read_images = [reader](const io::FrameEntry& frame) {
    io::FrameImages images;
    images.left = reader->Read(frame.index, io::ColourMode::kGrey);
    return images;
  };
}

// The live viewer of --viewer (nullptr without it), with the data set's ground truth.
std::unique_ptr<viewer::LiveViewer> MakeViewer(const RunArgs& args, const io::Sequence& sequence,
                                               const std::atomic<int>* stop) {
  if (!args.viewer_on) return nullptr;
  viewer::ViewerOptions options;
  options.server.host = args.viewer_host;
  if (!args.viewer.empty() && !args.viewer.front().empty()) {
    const auto port = ParseInt(args.viewer.front());
    if (!port || *port < 0 || *port > 65535) {
      ThrowInput("--viewer: '{}' is no port (0-65535)", args.viewer.front());
    }
    options.server.port = static_cast<int>(*port);
  }
  options.start_paused = args.viewer_paused;
  if (args.viewer_pause_at >= 0) options.pause_at = static_cast<size_t>(args.viewer_pause_at);
  auto live = std::make_unique<viewer::LiveViewer>(options, stop);
  live->SetGroundTruth(runner::ReadGroundTruth(sequence));
  return live;
}

// What a run reads: a sequence (a data set, a video, a bag) or a live source, with the settings
// for its sensor and how its frames are loaded.
struct RunInput {
  io::Sequence sequence;  // a live source's: name, root and sensor only, no frames
  std::unique_ptr<io::LiveSource> live;
  io::OrbSlamSettings settings;
  runner::RunOptions options;
  std::string format_name;  // summary.json's format when it is no io::DatasetFormat
  io::DatasetFormat format = io::DatasetFormat::kAuto;
};

// --dataset camera DEVICE[,DEVICE] (--side-by-side) or kinect INDEX: a live source, opened
// with the size the settings' intrinsics are for.
void SetUpLive(const RunArgs& args, const std::string& kind, const std::string& device,
               RunInput* input) {
  if (args.live) ThrowInput("--live: for recorded data ({} is live anyway)", kind);
  RefuseFileMasks(args, fmt::format("a live source ({})", device));
  io::SensorType sensor = io::SensorType::kRgbD;
  io::CameraOptions camera;
  if (kind == "camera") {
    camera.devices = SplitList(device, "--dataset camera");
    camera.side_by_side = args.side_by_side;
    sensor = camera.devices.size() == 2 || camera.side_by_side ? io::SensorType::kStereo
                                                               : io::SensorType::kMonocular;
  } else if (args.side_by_side) {
    ThrowInput("--side-by-side: for --dataset camera, not {}", kind);
  }
  input->settings = io::LoadOrbSlamSettings(args.settings, sensor);
  if (input->settings.camera.HasSize()) {
    camera.size = cv::Size(input->settings.camera.width, input->settings.camera.height);
  }
  camera.fps = input->settings.fps;
  if (kind == "camera") {
    input->live = io::OpenCamera(camera);
  } else {
    input->live = sensors::OpenKinect(sensors::ParseKinectIndex(device), camera.size);
  }
  input->format_name = kind;
  input->sequence.name = kind;
  input->sequence.root = input->live->name();
  input->sequence.sensor = sensor;
  if (!input->settings.camera.HasSize()) {
    const cv::Size size = input->live->image_size();
    io::CompleteImageSize(&input->settings, args.settings, size.width, size.height,
                          input->live->name());
  }
}

// --dataset rosbag FILE --topics A,B: the bag's image topics as a sequence whose frames are
// read in the loader thread (sensors/rosbag.h).
void SetUpRosbag(const RunArgs& args, const std::string& path, RunInput* input) {
  RefuseFileMasks(args, fmt::format("a bag ({})", path));
  sensors::RosbagOptions bag;
  if (args.topics.empty()) {
    ThrowInput("--dataset rosbag {}: needs --topics (its image topics, comma-separated)", path);
  }
  bag.topics = SplitList(args.topics, "--topics");
  bag.Check();
  auto reader = std::make_shared<sensors::RosbagReader>(path, bag);
  input->sequence = reader->sequence();
  if (args.monocular) input->sequence = io::ToMonocular(std::move(input->sequence));
  input->settings = io::LoadOrbSlamSettings(args.settings, input->sequence.sensor);
  input->format_name = "rosbag";
  const io::ColourMode colour = input->sequence.sensor == io::SensorType::kRgbD
                                    ? io::ColourMode::kColour
                                    : io::ColourMode::kGrey;
  const bool monocular = args.monocular;
  input->options.read_images = [reader, colour, monocular](const io::FrameEntry& frame) {
    io::FrameImages images = reader->Read(frame.index, colour);
    if (monocular) images.right = images.depth = cv::Mat();
    return images;
  };
}

RunInput ReadInput(const RunArgs& args) {
  const std::string& kind = args.dataset.at(0);
  const std::string& path = args.dataset.at(1);
  RunInput input;
  if (kind == "camera" || kind == "kinect") {
    SetUpLive(args, kind, path, &input);
    return input;
  }
  if (!args.topics.empty() && kind != "rosbag") ThrowInput("--topics: for --dataset rosbag");
  if (kind == "rosbag") {
    SetUpRosbag(args, path, &input);
  } else if (kind == "video") {
    input.settings = io::LoadOrbSlamSettings(args.settings, io::SensorType::kMonocular);
    SetUpVideo(args, path, &input.sequence, &input.options);
    input.format_name = "video";
  } else {
    const auto format = io::ParseDatasetFormat(kind);
    if (!format || *format == io::DatasetFormat::kAuto) {
      ThrowInput(
          "--dataset: unknown format '{}' (tum, kitti, euroc, folder, video, rosbag, camera, "
          "kinect)",
          kind);
    }
    // The settings are read first: an image folder takes its frame rate from Camera.fps.
    io::DatasetOptions dataset_options;
    dataset_options.format = input.format = *format;
    dataset_options.monocular = args.monocular;
    if (*format == io::DatasetFormat::kImageFolder) {
      input.settings = io::LoadOrbSlamSettings(args.settings, io::SensorType::kMonocular);
      dataset_options.image_folder_rate_hz = args.rate_hz > 0 ? args.rate_hz : input.settings.fps;
      input.sequence = io::ReadDataset(path, dataset_options);
    } else {
      input.sequence = io::ReadDataset(path, dataset_options);
      input.settings = io::LoadOrbSlamSettings(args.settings, input.sequence.sensor);
    }
  }
  if (input.sequence.empty()) ThrowInFile(path, "data set has no frames");
  SetImageSize(input.sequence, args.settings, &input.settings, &input.options);
  if (args.live) {
    // A live frame carries no image file name for a mask file to be named after.
    RefuseFileMasks(args, fmt::format("a data set played live ({})", path));
    // Loaded as the loader would, converted by the capture thread as a camera's frames are.
    io::ReplaySource::Load load = input.options.read_images;
    if (!load) {
      const io::ColourMode colour = input.sequence.sensor == io::SensorType::kRgbD
                                        ? io::ColourMode::kColour
                                        : io::ColourMode::kGrey;
      load = [colour, factor = input.settings.depth_map_factor](const io::FrameEntry& frame) {
        return io::LoadFrameImages(frame, colour, factor);
      };
    }
    input.live = std::make_unique<io::ReplaySource>(input.sequence, std::move(load));
  }
  return input;
}

void Run(const RunArgs& args, bool queue_given) {
  RunInput input = ReadInput(args);
  const io::Sequence& sequence = input.sequence;
  runner::RunOptions& options = input.options;
  const io::OrbSlamSettings& settings = input.settings;
  std::unique_ptr<runner::MaskSource> masks =
      runner::MakeMaskSource(MakeMaskOptions(args), sequence);
  if (!args.mask_damage.empty()) {
    masks =
        runner::MakeDamagedMaskSource(std::move(masks), runner::ParseMaskDamage(args.mask_damage));
  }
  if (!args.frames.empty()) options.frames = runner::ParseFrameRange(args.frames);
  if (!args.skip_frames.empty()) {
    options.skip = runner::ParseFrameRange(args.skip_frames, "--skip-frames");
  }
  options.realtime = args.realtime;
  options.segment_every = ParseSegmentEvery(args.segment_every, args.deterministic);
  options.progress = !args.quiet;
  // A live source keeps few frames waiting: each one is a frame of latency (default 2).
  options.queue_capacity = input.live && !queue_given ? 2 : args.queue;
  // RGB-D colour images go to the tracker in colour, converted to grey by Camera.RGB as ORB-SLAM2
  // does; the grey KITTI and EuRoC images are loaded grey.
  options.colour =
      sequence.sensor == io::SensorType::kRgbD ? io::ColourMode::kColour : io::ColourMode::kGrey;
  options.depth_factor = settings.depth_map_factor;
  if (input.live) {
    options.image_size = cv::Size(settings.camera.width, settings.camera.height);
    options.image_size_source = args.settings;
  }

  runner::RunDescription description;
  description.dataset_path = sequence.root;
  description.format = input.format;
  description.format_name = input.format_name;
  description.sensor = sequence.sensor;
  description.settings_path = args.settings;
  description.settings = settings;
  description.mask_source = masks->Describe();
  description.segment_every = args.segment_every;
  description.deterministic = args.deterministic;
  description.deterministic_mapping_frames = args.deterministic_mapping_frames;
  description.deterministic_mapping_ms = args.deterministic_mapping_ms;
  description.realtime = args.realtime || input.live != nullptr;
  spdlog::info("{}: {} ({}), masks: {}; OpenBLAS kernels: {}", sequence.root,
               input.live ? std::string("live") : fmt::format("{} frames", sequence.size()),
               io::ToString(sequence.sensor), description.mask_source, net::DescribeOpenBlasCore());

  runner::CheckGroundTruth(sequence);
  const std::string out = args.out.empty() ? "run_" + sequence.name : args.out;
  runner::CheckOutputFolder(out);  // before the run, not after it
  if (args.save_keyframe_masks) {
    options.keyframe_mask_folder = out + "/keyframe_masks";
    runner::CheckOutputFolder(options.keyframe_mask_folder);
  }
  const std::unique_ptr<runner::Tracker> tracker = MakeTracker(settings, sequence.sensor, args);
  std::unique_ptr<viewer::LiveViewer> live;
  runner::RunResult result;
  int signal = 0;
  {
    // SIGINT / SIGTERM from here on end the run after the frame in hand, with its outputs written.
    const runner::ScopedStopSignals signals;
    options.stop = signals.flag();
    live = MakeViewer(args, sequence, signals.flag());
    options.observer = live.get();
    result = input.live ? runner::RunLive(*input.live, *tracker, *masks, options)
                        : runner::RunSequence(sequence, *tracker, *masks, options);
    signal = signals.received();
  }
  if (result.end == runner::RunEnd::kInterrupted) {
    result.end_message = fmt::format("interrupted by {} after {} frames",
                                     runner::SignalName(signal), result.frames.size());
    spdlog::warn("{}; writing the outputs of the frames tracked", result.end_message);
  } else if (result.end == runner::RunEnd::kFailed) {
    spdlog::warn("the run failed after {} frames; writing the outputs of the frames tracked",
                 result.frames.size());
  }
  const std::string summary = runner::WriteRunOutputs(sequence, result, description, out);
  std::cout << summary << std::flush;
  if (live) {
    live->Finish(result, *tracker);
    if (result.end != runner::RunEnd::kInterrupted && !args.viewer_exit) {
      spdlog::info("viewer: the run has ended; {} keeps showing it until Ctrl-C", live->url());
      live->WaitForStopSignal();
    }
  }
  runner::RethrowFailure(result);  // exit status and message as for an error before the run
  if (result.end == runner::RunEnd::kInterrupted) throw ExitStatus{128 + signal};
}

}  // namespace

void AddViewerOptions(CLI::App* command, RunArgs* args) {
  command
      ->add_option("--viewer", args->viewer,
                   "Watch the run in a browser at http://127.0.0.1:PORT/ (default port 8765): "
                   "map, keyframes, trajectory, the current image with its keypoints and mask, "
                   "pause / step / resume. When the run ends the page stays until Ctrl-C "
                   "(docs/RUNNING.md; over SSH: ssh -L 8765:127.0.0.1:8765 HOST)")
      ->expected(0, 1);
  command
      ->add_option("--viewer-host", args->viewer_host,
                   "Address the viewer listens on. The default 127.0.0.1 keeps it to this "
                   "machine; another address (0.0.0.0: all) EXPOSES THE VIEWER, with its "
                   "pause button, TO EVERYONE WHO CAN REACH THAT PORT, with no password")
      ->capture_default_str();
  command->add_flag("--viewer-paused", args->viewer_paused,
                    "Stop after the first frame until the page resumes or steps");
  command
      ->add_option("--viewer-pause-at", args->viewer_pause_at,
                   "Stop at frame N (the data set's index; the first frame from N on) until the "
                   "page resumes or steps, as if Pause had been pressed there; a run cannot end "
                   "before it, however late a page looks (the browser test relies on it)")
      ->check(CLI::NonNegativeNumber)
      ->needs("--viewer");
  command->add_flag("--viewer-exit", args->viewer_exit,
                    "End when the run ends instead of keeping the page up until Ctrl-C");
}

void AddRunCommand(CLI::App& app) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* command = app.add_subcommand(
      "run",
      "Run SLAM over a data set: trajectories (TUM; KITTI too for KITTI input), per-frame log, "
      "summary with timings, and the ATE when the data set has ground truth (docs/RUNNING.md)");
  command
      ->add_option("--dataset", args->dataset,
                   "FORMAT PATH: tum, kitti, euroc or folder, and the data-set folder; video "
                   "and a video file (monocular); rosbag and a ROS 1 bag (with --topics); "
                   "camera and a V4L2 device (/dev/video0 or 0; two, comma-separated: stereo); "
                   "kinect and a Kinect v1's index (0: the first). Live sources run in real "
                   "time, dropping the frames tracking has no time for; Ctrl-C ends them")
      ->expected(2)
      ->required();
  command->add_option("--settings", args->settings, "ORB-SLAM2 settings YAML (configs/*.yaml)")
      ->required()
      ->check(ExistingFileOf("settings file"));
  command
      ->add_option("--mask-source", args->mask_source,
                   "Movable-object masks: none, files DIR (DIR/<image stem>.png), synth-gt (the "
                   "synthetic generator's class/<stem>.png with classes.txt), onnx (a "
                   "segmentation network), detector (box masks), both with --model-card, or model "
                   "(a libtorch network of the weakly supervised pipeline, a torch card; "
                   "default card configs/models/weak_camvid.yaml); computed in a thread of their "
                   "own, one frame ahead of tracking")
      ->expected(1, 2)
      ->default_str("none");
  command->add_option("--model-card", args->model_card,
                      "onnx, detector, model: the model card (configs/models/*.yaml); model files "
                      "are found beside it or under MOSLAM_SHARED");
  command
      ->add_option(
          "--crf", args->crf,
          "onnx, detector, model: refine with the CRF's colour (c), depth (d) or both (cd) "
          "kernels, or none (default: the card's setting, normally none)")
      ->check(CLI::IsMember({"none", "c", "d", "cd"}));
  command
      ->add_option("--mask-missing", args->mask_missing,
                   "files: a frame without a mask file is an error, or runs with an empty mask")
      ->check(CLI::IsMember({"error", "empty"}))
      ->capture_default_str();
  command
      ->add_option(
          "--movable", args->movable,
          "synth-gt, onnx, detector, model: movable class names, comma-separated (default: "
          "those classes.txt or the model card marks movable)")
      ->delimiter(',');
  command->add_option("--mask-dilate", args->mask_dilate, "Grow every mask by this many pixels")
      ->capture_default_str();
  command->add_option("--out", args->out, "Output folder")->default_str("run_<sequence name>");
  command->add_option("--frames", args->frames,
                      "Sub-range A:B of frame indices (B excluded; A: and :B too)");
  command->add_option("--skip-frames", args->skip_frames,
                      "Frames A..B-1 are never given to the tracker (a gap in the recording, to "
                      "exercise relocalization)");
  command
      ->add_option("--vocabulary", args->vocabulary,
                   "Bag-of-words vocabulary (moslam binary .mvoc or ORB-SLAM2's ORBvoc.txt) for "
                   "relocalization and loop closing; 'default': the shipped "
                   "data/vocab/moslam_orb.mvoc (relative to the working directory, skipped with a "
                   "warning when absent); 'none': neither")
      ->capture_default_str();
  command->add_option(
      "--rate", args->rate_hz,
      "folder: frames per second of the images (default: the settings' Camera.fps); "
      "video: frame k at k / rate seconds (default: the container's times)");
  command->add_flag("--side-by-side", args->side_by_side,
                    "camera: one device whose frames hold the left and right images side by "
                    "side (stereo; the settings' Camera.width is one half's)");
  command->add_flag("--live", args->live,
                    "Play a recorded data set as a live camera: each frame delivered at its "
                    "timestamp, frames tracking has no time for dropped and counted (as "
                    "--dataset camera; to see how a machine keeps up in real time)");
  command->add_option("--topics", args->topics,
                      "rosbag: the sensor_msgs/Image topics, comma-separated: one (monocular), "
                      "colour and depth (RGB-D: depth 16UC1 in mm or 32FC1 in m) or left and "
                      "right (stereo)");
  command
      ->add_option("--queue", args->queue,
                   "Frames loaded ahead of tracking; live sources: frames waiting for "
                   "tracking, beyond which the oldest are dropped (default 2 there)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  command->add_flag("--realtime", args->realtime,
                    "Pace frames by their timestamps instead of running as fast as possible");
  command->add_flag("--deterministic", args->deterministic,
                    "Fixed seeds, local mapping synchronous in the tracking thread, the network on "
                    "one libtorch thread whatever its card says");
  command
      ->add_option("--deterministic-mapping-frames", args->deterministic_mapping_frames,
                   "With --deterministic: tracked frames local mapping takes per keyframe, as "
                   "its thread would (keyframes wait in a queue on that clock; tracking adds one "
                   "only when it must while mapping is busy); 0: by the size of its last local "
                   "bundle adjustment; 1: each keyframe mapped at once")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--deterministic-mapping-ms", args->deterministic_mapping_ms,
                   "With --deterministic and --deterministic-mapping-frames 0: milliseconds of "
                   "mapping per observation of the last local bundle adjustment, turned into "
                   "frames at the settings' Camera.fps")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--local-ba-keyframes", args->local_ba_keyframes,
                   "Local bundle adjustment moves the new keyframe and at most N of its best "
                   "covisible keyframes, the others that see its points fixed; 0: every "
                   "covisible keyframe (ORB-SLAM2)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command->add_flag("--monocular", args->monocular,
                    "Monocular SLAM on the left / colour images only, ignoring right images and "
                    "depth (a KITTI folder without image_1 is monocular anyway)");
  command->add_flag("--quiet", args->quiet, "No progress line and only warnings in the log");
  command
      ->add_option("--far-stereo", args->far_stereo,
                   "How tracking and bundle adjustment use the disparity of stereo observations "
                   "beyond ThDepth (ORB-SLAM2's far points): full (as near ones, ORB-SLAM2), "
                   "weighted (information x (ThDepth depth / depth)^2), monocular (dropped); "
                   "auto: weighted for stereo, full for RGB-D")
      ->check(CLI::IsMember({"auto", "full", "weighted", "monocular"}))
      ->capture_default_str();
  command->add_flag("--no-loop-closing", args->no_loop_closing,
                    "Run without loop closing even with a vocabulary (to measure what it does)");
  command->add_flag("--no-loop-verification", args->no_loop_verification,
                    "Close every loop that ORB-SLAM2's tests accept, without checking it against "
                    "the drift the odometry allows, depths, neighbours and spread (comparisons)");
  command->add_flag("--no-loop-word-weights", args->no_loop_word_weights,
                    "Score loop candidates with ORB-SLAM2's bag-of-words weights, without "
                    "down-weighting the words of places passed a short while ago (repeated "
                    "structure; comparisons)");
  command->add_flag("--no-short-loss-recovery", args->no_short_loss_recovery,
                    "Relocalize a frame lost a moment ago wherever it matches, as ORB-SLAM2, "
                    "instead of near where the last velocity puts it (comparisons)");
  command->add_flag("--no-movable-evidence", args->no_movable_evidence,
                    "Keep map points that later masks show to lie on a movable object (by "
                    "default they are erased after 2 such frames; ablations)");
  command->add_flag("--free-space-check", args->free_space_check,
                    "RGB-D: erase map points where 3 frames' depth shows free space in front of "
                    "the surface they should be on (off by default: it costs static points at "
                    "depth edges)");
  command->add_flag("--no-moving-check", args->no_moving_check,
                    "Let keyframe keypoints seen moving against 3 frames back seed map points "
                    "(ablations)");
  command->add_flag("--no-static-scores", args->no_static_scores,
                    "Give every matched map point full weight in pose optimization and keep "
                    "points whose residuals show them moving frame after frame (ablations)");
  command->add_flag("--no-completion-planes", args->no_completion_planes,
                    "RGB-D: let the mask completion grow onto the large planes of the depth image "
                    "(floor, walls) too, bounded only by --mask-completion (ablations)");
  command->add_flag("--no-propagation-depth-check", args->no_propagation_depth_check,
                    "RGB-D: keep every carried mask pixel, also where the new depth shows the "
                    "body has left it (ablations)");
  command->add_flag("--no-moving-regions", args->no_moving_regions,
                    "Do not turn clusters of keypoints found moving into mask regions carried "
                    "into the next frames (ablations)");
  command->add_flag("--no-motion-cross-check", args->no_motion_cross_check,
                    "Take the motion model's pose however few of the last frame's inliers it "
                    "keeps, without trying the reference keyframe too (ablations)");
  command->add_flag("--no-pose-consensus", args->no_pose_consensus,
                    "Stereo/RGB-D: optimize each frame's pose from all its matches by least "
                    "squares alone, without first finding by counting which of them agree "
                    "(ablations)");
  command->add_flag("--young-points", args->young_points,
                    "Stereo/RGB-D: leave recently made map points out of a frame's pose when they "
                    "fit a pose of their own much better than the long-known points do (an object "
                    "no network marks, e.g. a pushed cart; off by default)");
  command
      ->add_option("--mask-margin", args->mask_margin,
                   "No new map point within this many pixels of a mask (0: off)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--mask-propagation", args->mask_propagation,
                   "Carry each mask into this many following frames with the predicted motion "
                   "(RGB-D with the depth under it; 0: off)")
      ->check(CLI::Range(0, 250))
      ->capture_default_str();
  command
      ->add_option("--mask-completion", args->mask_completion,
                   "RGB-D: grow masks over the depth-connected surface they cover, up to this "
                   "many pixels (0: off)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  command
      ->add_option("--mask-work-scale", args->mask_work_scale,
                   "Carry and grow masks on images downsampled by this factor (1: full size; "
                   "the network's pixels stay exact)")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  command
      ->add_option("--segment-every", args->segment_every,
                   "Run the mask source on every K-th frame only; the others get the carried "
                   "mask (needs --mask-propagation > 0). auto: the smallest K at which the "
                   "source keeps up with tracking, from the times measured as the run goes "
                   "(not with --deterministic)")
      ->capture_default_str();
  command->add_option("--mask-damage", args->mask_damage,
                      "Damage the masks for ablations: miss=P,border=PX,erode=PX,holes=P,"
                      "radius=PX,seed=N (P a share 0..1; any subset)");
  command
      ->add_option("--mapping-nice", args->mapping_nice,
                   "Nice increment (0-19) of the local-mapping and loop-closing threads, so "
                   "that tracking and segmentation get the cores first (0: equal priority, "
                   "as ORB-SLAM2; no effect with --deterministic)")
      ->check(CLI::Range(0, 19))
      ->capture_default_str();
  command->add_option("--save-map", args->save_map,
                      "Write the whole map to FILE when the run ends (docs/MAP_FORMAT.md; written "
                      "to FILE.tmp, then renamed)");
  command->add_option("--load-map", args->load_map,
                      "Start from a map saved by --save-map: the first frames are relocalized in "
                      "it, then tracking and mapping continue (same settings and vocabulary)");
  command->add_flag("--localization", args->localization,
                    "With --load-map: track and relocalize in the loaded map without changing "
                    "it (no new keyframes or points, no loop closing)");
  command->add_flag("--save-keyframe-masks", args->save_keyframe_masks,
                    "Write each keyframe's movable mask (as its features were extracted: the "
                    "source's mask, carried and grown) to OUT/keyframe_masks/<stamp>.png, for "
                    "`moslam map export` to fuse the keyframes' depth without the movable objects");
  AddViewerOptions(command, args.get());
  command->callback([args, command] {
    args->viewer_on = command->count("--viewer") > 0;
    if (args->quiet) spdlog::set_level(std::max(spdlog::get_level(), spdlog::level::warn));
    Run(*args, command->count("--queue") > 0);
  });
}

}  // namespace moslam::app
