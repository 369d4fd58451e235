// moslam segment: runs a mask provider (an ONNX segmentation network, a detector or a libtorch
// network of the weakly supervised pipeline, described by a model card) over a sequence or a folder
// of images, writes each frame's movable-object mask and overlays, times every frame, and, given
// label images, scores the masks (binary movable IoU, per-class recall) into segment.json.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "moslam/eval/statistics.h"
#include "moslam/io/dataset.h"
#include "moslam/io/image.h"
#include "moslam/net/torch_mask_provider.h"
#include "moslam/runner/outputs.h"
#include "moslam/runner/run_loop.h"
#include "moslam/semantic/mask_provider.h"
#include "moslam/semantic/overlay.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"

namespace moslam::app {
namespace {

namespace fs = std::filesystem;

struct SegmentArgs {
  std::vector<std::string> dataset;  // FORMAT PATH
  std::string images;                // or a folder of images
  std::string model_card;
  std::string crf;
  std::vector<std::string> movable;
  int dilate = -1;
  int working_side = -1;
  std::string frames;
  std::string out;
  int overlay_every = 1;
  std::string labels;              // folder of label PNGs named like the images
  std::vector<int> label_movable;  // label ids that are movable
  std::vector<int> label_ignore;   // label ids left out of the scores
};

// The frames to segment: a data set's (its depth too, for --crf d) or an image folder's files.
std::vector<io::FrameEntry> Frames(const SegmentArgs& args, io::SensorType* sensor) {
  std::vector<io::FrameEntry> frames;
  if (!args.images.empty()) {
    RequireDirectory(args.images, "image folder");
    std::vector<std::string> paths;
    for (const auto& e : fs::directory_iterator(args.images)) {
      const std::string ext = ToLower(e.path().extension().string());
      if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") paths.push_back(e.path().string());
    }
    std::sort(paths.begin(), paths.end());
    for (size_t i = 0; i < paths.size(); ++i) {
      frames.push_back({static_cast<int>(i), static_cast<double>(i), paths[i], "", ""});
    }
    *sensor = io::SensorType::kMonocular;
  } else {
    const auto format = io::ParseDatasetFormat(args.dataset.at(0));
    if (!format) ThrowInput("--dataset: unknown format '{}'", args.dataset[0]);
    io::DatasetOptions options;
    options.format = *format;
    const io::Sequence sequence = io::ReadDataset(args.dataset.at(1), options);
    frames = sequence.frames;
    *sensor = sequence.sensor;
  }
  if (frames.empty()) ThrowInput("no images to segment");
  if (!args.frames.empty()) {
    const runner::FrameRange range = runner::ParseFrameRange(args.frames);
    const size_t last = std::min(range.last.value_or(frames.size()), frames.size());
    if (range.first >= last)
      ThrowInput("--frames: {} is outside the {} frames", args.frames, frames.size());
    frames = std::vector<io::FrameEntry>(frames.begin() + static_cast<long>(range.first),
                                         frames.begin() + static_cast<long>(last));
  }
  return frames;
}

// Scores of the binary movable mask against label images, summed over all frames.
struct Scores {
  std::vector<int> movable_ids, ignore_ids;
  double intersection = 0, union_ = 0, predicted = 0, truth = 0;
  std::map<int, std::pair<double, double>> per_label;  // id -> (pixels, pixels marked movable)

  void Add(const cv::Mat& labels, const cv::Mat& mask) {
    cv::Mat truth_mask(labels.size(), CV_8U, cv::Scalar(0)),
        valid(labels.size(), CV_8U, cv::Scalar(255));
    for (int id : movable_ids) truth_mask.setTo(255, labels == id);
    for (int id : ignore_ids) valid.setTo(0, labels == id);
    const cv::Mat m = mask & valid;
    const cv::Mat t = truth_mask & valid;
    intersection += cv::countNonZero(m & t);
    union_ += cv::countNonZero(m | t);
    predicted += cv::countNonZero(m);
    truth += cv::countNonZero(t);
    for (int id : movable_ids) {
      const cv::Mat of = labels == id;
      per_label[id].first += cv::countNonZero(of);
      per_label[id].second += cv::countNonZero(of & mask);
    }
  }
  nlohmann::json Json() const {
    nlohmann::json recall = nlohmann::json::object();
    for (const auto& [id, counts] : per_label) {
      recall[std::to_string(id)] = counts.first > 0 ? counts.second / counts.first : 0.0;
    }
    return {{"movable_iou", union_ > 0 ? intersection / union_ : 0.0},
            {"precision", predicted > 0 ? intersection / predicted : 0.0},
            {"recall", truth > 0 ? intersection / truth : 0.0},
            {"recall_per_label", recall},
            {"movable_labels", movable_ids},
            {"ignored_labels", ignore_ids}};
  }
};

cv::Mat ReadLabels(const std::string& folder, const io::FrameEntry& frame, const cv::Size& size) {
  const std::string path = (fs::path(folder) / fs::path(frame.image_left).stem()).string() + ".png";
  const cv::Mat labels = cv::imread(path, cv::IMREAD_GRAYSCALE);
  if (labels.empty()) ThrowInFile(path, "label image of " + frame.image_left + " cannot be read");
  if (labels.size() != size) ThrowInFile(path, "label image and image differ in size");
  return labels;
}

// Left: the provider's classes (argmax at the working size); right: the movable mask, with a
// detector's boxes outlined.
cv::Mat Overlay(const cv::Mat& image, const semantic::MaskResult& r) {
  const cv::Mat bgr = semantic::ToBgr(image);
  cv::Mat labels;
  cv::resize(r.labels, labels, bgr.size(), 0, 0, cv::INTER_NEAREST);
  cv::Mat masked = semantic::DrawMaskOverlay(bgr, r.mask, cv::Scalar(0, 0, 255));
  for (const semantic::Detection& d : r.detections) {
    cv::rectangle(masked, d.box, cv::Scalar(0, 255, 255), 1);
  }
  return semantic::SideBySide({semantic::DrawLabelOverlay(bgr, labels), masked},
                              {"classes (argmax)", "movable mask"});
}

nlohmann::json TimeStats(const std::vector<double>& values) {
  const eval::ErrorStatistics s = eval::ComputeStatistics(values);
  return {{"median", s.median},
          {"mean", s.mean},
          {"p90", runner::Percentile(values, 90.0)},
          {"max", s.max}};
}

void Run(const SegmentArgs& args) {
  if (args.images.empty() == args.dataset.empty()) {
    ThrowInput("give either --images DIR or --dataset FORMAT PATH");
  }
  // A torch card is completed from its model file here, so that --movable can name its classes.
  semantic::ModelCard card = net::LoadAnyModelCard(args.model_card);
  if (!args.movable.empty()) semantic::SetMovable(args.movable, &card);
  semantic::RefineOptions refine = card.refine;
  if (!args.crf.empty()) refine.crf = semantic::ParseCrfMode(args.crf).value();
  if (args.dilate >= 0) refine.dilate_px = args.dilate;
  if (args.working_side >= 0) refine.working_side = args.working_side;
  const std::unique_ptr<semantic::MaskProvider> provider = net::MakeAnyMaskProvider(card, refine);
  io::SensorType sensor = io::SensorType::kMonocular;
  const std::vector<io::FrameEntry> frames = Frames(args, &sensor);
  spdlog::info("{} frames, {}", frames.size(), provider->Describe());

  const fs::path out(args.out);
  fs::create_directories(out / "masks");
  fs::create_directories(out / "overlays");
  Scores scores;
  scores.movable_ids = args.label_movable;
  scores.ignore_ids = args.label_ignore;
  std::vector<double> network_ms, crf_ms, total_ms, fraction;
  Progress progress("segmenting", frames.size(), 2.0, "frames");
  for (size_t i = 0; i < frames.size(); ++i) {
    const io::FrameEntry& frame = frames[i];
    const io::FrameImages images = io::LoadFrameImages(frame, io::ColourMode::kColour);
    const semantic::MaskResult r = provider->Segment({images.left, images.depth});
    network_ms.push_back(r.network_ms);
    crf_ms.push_back(r.crf_ms);
    total_ms.push_back(r.total_ms);
    fraction.push_back(cv::countNonZero(r.mask) / static_cast<double>(r.mask.total()));
    const std::string stem = fs::path(frame.image_left).stem().string();
    const std::string mask_path = (out / "masks" / (stem + ".png")).string();
    if (!cv::imwrite(mask_path, r.mask)) ThrowInFile(mask_path, "cannot be written");
    if (args.overlay_every > 0 && i % static_cast<size_t>(args.overlay_every) == 0) {
      const std::string path = (out / "overlays" / (stem + ".png")).string();
      if (!cv::imwrite(path, Overlay(images.left, r))) {
        ThrowInFile(path, "cannot be written");
      }
    }
    if (!args.labels.empty()) scores.Add(ReadLabels(args.labels, frame, r.mask.size()), r.mask);
    progress.Update(i + 1);
  }
  progress.Finish();
  nlohmann::json json = {{"model_card", args.model_card},
                         {"provider", provider->Describe()},
                         {"frames", frames.size()},
                         {"times_ms",
                          {{"network", TimeStats(network_ms)},
                           {"crf", TimeStats(crf_ms)},
                           {"total", TimeStats(total_ms)}}},
                         {"movable_fraction_mean", eval::ComputeStatistics(fraction).mean}};
  if (!args.labels.empty()) json["scores"] = scores.Json();
  const std::string json_path = (out / "segment.json").string();
  std::ofstream(json_path) << json.dump(2) << "\n";
  std::printf("%s\n%zu frames: network %.1f ms, CRF %.1f ms, total %.1f ms per frame (median)\n",
              provider->Describe().c_str(), frames.size(),
              json["times_ms"]["network"]["median"].get<double>(),
              json["times_ms"]["crf"]["median"].get<double>(),
              json["times_ms"]["total"]["median"].get<double>());
  if (!args.labels.empty()) {
    const nlohmann::json s = json["scores"];
    std::printf("movable IoU %.3f (precision %.3f, recall %.3f)\n", s["movable_iou"].get<double>(),
                s["precision"].get<double>(), s["recall"].get<double>());
  }
  std::printf("masks, overlays and segment.json in %s\n", args.out.c_str());
}

}  // namespace

void AddSegmentCommand(CLI::App& app) {
  auto args = std::make_shared<SegmentArgs>();
  CLI::App* cmd = app.add_subcommand(
      "segment",
      "Movable-object masks of a sequence or an image folder from a model card (ONNX "
      "segmentation, detector or torch): masks/<stem>.png (255 = movable), overlays/<stem>.png, "
      "segment.json with per-frame times and, with --labels, the movable IoU");
  cmd->add_option("--dataset", args->dataset, "FORMAT PATH: tum, kitti, euroc or folder")
      ->expected(2);
  cmd->add_option("--images", args->images, "A folder of .png/.jpg images (name order)");
  cmd->add_option("--model-card", args->model_card,
                  "Model card (configs/models/*.yaml; type segmentation, detector or torch)")
      ->required();
  cmd->add_option("--crf", args->crf, "CRF kernels: none, c, d, cd (default: the card's)")
      ->check(CLI::IsMember({"none", "c", "d", "cd"}));
  cmd->add_option("--movable", args->movable, "Movable class names (default: the card's)")
      ->delimiter(',');
  cmd->add_option("--mask-dilate", args->dilate, "Grow masks by this many pixels (default: card)");
  cmd->add_option("--working-side", args->working_side,
                  "Longest side of the working resolution, pixels (0: the image's; default: "
                  "the card's)");
  cmd->add_option("--frames", args->frames, "Sub-range A:B of the frames (B excluded)");
  cmd->add_option("--out", args->out, "Output folder")->required();
  cmd->add_option("--overlay-every", args->overlay_every,
                  "Write an overlay for every N-th frame (0: none)")
      ->capture_default_str();
  cmd->add_option("--labels", args->labels,
                  "Folder of 8-bit label PNGs named like the images, to score the masks");
  cmd->add_option("--label-movable", args->label_movable,
                  "Label ids that are movable (CamVid: 8,9,10)")
      ->delimiter(',');
  cmd->add_option("--label-ignore", args->label_ignore,
                  "Label ids left out of the scores (e.g. CamVid's 11, unlabelled)")
      ->delimiter(',');
  cmd->callback([args] {
    if (!args->labels.empty() && args->label_movable.empty()) {
      ThrowInput("--labels needs --label-movable (the ids of the movable labels)");
    }
    Run(*args);
  });
}

}  // namespace moslam::app
