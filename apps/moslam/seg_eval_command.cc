// moslam seg-eval: scores a segmentation network against pixel labels (CamVid ids): per-class IoU,
// mean IoU and the binary movable-vs-static IoU (weak/evaluation.h), with the network's
// probabilities upsampled to each image's size (bilinear), optional test-time suppression by the
// network's image-level class scores and the colour CRF, then the argmax. Writes the scores as
// JSON, the confusion matrix as an image and overlays of the best and worst frames.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "commands.h"
#include "moslam/eval/statistics.h"
#include "moslam/net/torch_mask_provider.h"
#include "moslam/semantic/mask_provider.h"
#include "moslam/semantic/overlay.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"
#include "moslam/util/strings.h"
#include "moslam/util/text_file.h"
#include "moslam/weak/evaluation.h"

namespace moslam::app {
namespace {

namespace fs = std::filesystem;

struct SegEvalArgs {
  std::string model;  // .mnet model file or a model card
  std::string images;
  std::string labels;
  std::string json;
  std::string out;
  bool grey = false;
  std::string crf = "none";
  float suppress_below = 0.0f;
  std::optional<float> movable_bias;  // the card's refine.movable_bias when not given
  std::vector<int> label_movable = {8, 9, 10};
  std::vector<int> label_ignore = {11};
  // Class names of the label ids, in id order (CamVid's when empty).
  std::vector<std::string> label_names;
  int threads = 2;
  int limit = 0;
  // Run a torch network at this input size instead of its model's (0: the model's).
  int input_width = 0;
  int input_height = 0;
};

// Ground-truth id -> model class: by CamVid class name when the model names CamVid classes (ids
// whose class the model lacks go to its background class, else count as misses); otherwise the
// identity (the model's classes are taken to be the label ids).
std::vector<int> LabelToClass(const semantic::ModelCard& card,
                              const std::vector<std::string>& label_names) {
  std::vector<int> mapping =
      weak::LabelToClassByName(label_names.empty() ? weak::CamVidLabelNames() : label_names,
                               card.classes, card.BackgroundIndex());
  if (mapping.empty()) {
    spdlog::warn("{}: no class is named like a CamVid class; label id i is taken to be class i",
                 card.name);
  }
  return mapping;
}

// The model as a card: a model card file (torch or ONNX segmentation), or a bare .mnet file.
semantic::ModelCard LoadCard(const std::string& model) {
  const std::string ext = ToLower(fs::path(model).extension().string());
  if (ext != ".yaml" && ext != ".yml") return net::TorchModelCard(model);
  semantic::ModelCard card = net::LoadAnyModelCard(model);
  if (card.kind == semantic::ModelKind::kDetector) {
    ThrowInFile(model, "type: detector; seg-eval needs a segmentation network (torch or ONNX)");
  }
  return card;
}

std::unique_ptr<semantic::MaskProvider> MakeProvider(const semantic::ModelCard& card,
                                                     const SegEvalArgs& args) {
  semantic::RefineOptions refine = card.refine;
  refine.working_side = 0;  // the probabilities at the image's size: labels are full resolution
  refine.suppress_below = args.suppress_below;
  if (args.movable_bias) refine.movable_bias = *args.movable_bias;
  refine.crf = semantic::ParseCrfMode(args.crf).value();
  refine.crf_binary = false;  // every class, so that the CRF changes the labels, not only the mask
  refine.dilate_px = 0;
  if (card.kind == semantic::ModelKind::kTorch) {
    return std::make_unique<net::TorchMaskProvider>(card, refine, args.threads);
  }
  return net::MakeAnyMaskProvider(card, refine);
}

std::vector<std::string> ImagePaths(const SegEvalArgs& args) {
  RequireDirectory(args.images, "image folder");
  RequireDirectory(args.labels, "label folder");
  std::vector<std::string> paths;
  for (const auto& e : fs::directory_iterator(args.images)) {
    const std::string ext = ToLower(e.path().extension().string());
    if (ext == ".png" || ext == ".jpg" || ext == ".jpeg") paths.push_back(e.path().string());
  }
  std::sort(paths.begin(), paths.end());
  if (paths.empty()) ThrowInput("{}: no .png/.jpg images", args.images);
  if (args.limit > 0 && paths.size() > static_cast<size_t>(args.limit)) paths.resize(args.limit);
  return paths;
}

// A frame for the picture gallery: the frames with movable ground truth, ranked by movable IoU.
struct Shown {
  double iou = 0.0;
  std::string stem;
  cv::Mat overlay;
};

// Prediction | truth (classes) | movable: true positives green, false positives red, misses blue.
cv::Mat FrameOverlay(const cv::Mat& image, const cv::Mat& predicted, const cv::Mat& truth_classes,
                     const cv::Mat& predicted_movable, const cv::Mat& truth_movable, double iou) {
  const cv::Mat bgr = semantic::ToBgr(image);
  cv::Mat movable =
      semantic::DrawMaskOverlay(bgr, predicted_movable & truth_movable, cv::Scalar(0, 200, 0));
  movable =
      semantic::DrawMaskOverlay(movable, predicted_movable & ~truth_movable, cv::Scalar(0, 0, 255));
  movable =
      semantic::DrawMaskOverlay(movable, ~predicted_movable & truth_movable, cv::Scalar(255, 0, 0));
  return semantic::SideBySide(
      {semantic::DrawLabelOverlay(bgr, predicted), semantic::DrawLabelOverlay(bgr, truth_classes),
       movable},
      {"prediction", "truth", fmt::format("movable IoU {:.2f} (TP green, FP red, FN blue)", iou)});
}

// Keeps the `keep` highest (best) or lowest (worst) IoUs.
void Offer(Shown shown, bool best, size_t keep, std::vector<Shown>* list) {
  list->push_back(std::move(shown));
  std::stable_sort(list->begin(), list->end(), [best](const Shown& a, const Shown& b) {
    return best ? a.iou > b.iou : a.iou < b.iou;
  });
  if (list->size() > keep) list->resize(keep);
}

void WriteImage(const fs::path& path, const cv::Mat& image) {
  if (!cv::imwrite(path.string(), image)) ThrowInFile(path.string(), "cannot be written");
}

void PrintScores(const weak::SegEvaluator& eval, const std::string& describe, double mean_ms,
                 double median_ms) {
  std::printf("%s\n%d images\n%-12s %7s\n", describe.c_str(), eval.images(), "class", "IoU");
  const std::vector<double> iou = eval.ClassIoU();
  for (int c = 0; c < eval.num_classes(); ++c) {
    const std::string value = std::isnan(iou[c]) ? "-" : fmt::format("{:.3f}", iou[c]);
    std::printf("%-12s %7s\n", eval.class_names()[c].c_str(), value.c_str());
  }
  std::printf("mean IoU %.3f, pixel accuracy %.3f\n", eval.MeanIoU(), eval.PixelAccuracy());
  std::printf("movable IoU %.3f (precision %.3f, recall %.3f)\n", eval.MovableIoU(),
              eval.MovablePrecision(), eval.MovableRecall());
  std::printf("%.1f ms per image (mean; median %.1f): network, upsampling, suppression, CRF\n",
              mean_ms, median_ms);
}

void Run(const SegEvalArgs& args) {
  semantic::ModelCard card = LoadCard(args.model);
  if (args.input_width > 0 || args.input_height > 0) {
    if (card.kind != semantic::ModelKind::kTorch) {
      ThrowInput("--input-width/--input-height: only a torch network runs at another size ({})",
                 args.model);
    }
    if (args.input_width <= 0 || args.input_height <= 0) {
      ThrowInput("--input-width/--input-height: give both (are {} and {})", args.input_width,
                 args.input_height);
    }
    card.input_width = args.input_width;
    card.input_height = args.input_height;
  }
  const std::unique_ptr<semantic::MaskProvider> provider = MakeProvider(card, args);
  const std::vector<std::string> paths = ImagePaths(args);
  spdlog::info("{} images{}, {}", paths.size(), args.grey ? " (grey)" : "", provider->Describe());

  weak::SegEvalOptions options;
  options.ignore_labels = args.label_ignore;
  options.label_to_class = LabelToClass(card, args.label_names);
  options.movable_labels.assign(256, false);
  for (int id : args.label_movable) {
    if (id < 0 || id > 255) ThrowInput("--label-movable: {} is not an 8-bit label id", id);
    options.movable_labels[id] = true;
  }
  options.movable_classes = provider->movable();
  weak::SegEvaluator eval(provider->class_names(), options);
  cv::Mat truth_lut(1, 256, CV_8U, cv::Scalar(255));  // label id -> class, for the overlays
  for (int id = 0; id < 256; ++id) {
    const int c =
        options.label_to_class.empty()
            ? id
            : (id < static_cast<int>(options.label_to_class.size()) ? options.label_to_class[id]
                                                                    : -1);
    if (c >= 0 && c < eval.num_classes()) truth_lut.at<uint8_t>(0, id) = static_cast<uint8_t>(c);
  }
  cv::Mat class_movable_lut(1, 256, CV_8U, cv::Scalar(0));
  for (size_t c = 0; c < provider->movable().size(); ++c) {
    if (provider->movable()[c]) class_movable_lut.at<uint8_t>(0, static_cast<int>(c)) = 255;
  }

  std::vector<double> total_ms, network_ms, crf_ms;
  nlohmann::json frames = nlohmann::json::array();
  std::vector<Shown> best, worst;
  Progress progress("evaluating", paths.size(), 2.0, "images");
  for (size_t i = 0; i < paths.size(); ++i) {
    const std::string stem = fs::path(paths[i]).stem().string();
    cv::Mat image = cv::imread(paths[i], cv::IMREAD_COLOR);
    if (image.empty()) ThrowInFile(paths[i], "cannot be read as an image");
    if (args.grey) cv::cvtColor(image, image, cv::COLOR_BGR2GRAY);
    const std::string label_path = (fs::path(args.labels) / (stem + ".png")).string();
    const cv::Mat labels = cv::imread(label_path, cv::IMREAD_GRAYSCALE);
    if (labels.empty()) ThrowInFile(label_path, "label image of " + paths[i] + " cannot be read");
    if (labels.size() != image.size()) ThrowInFile(label_path, "differs in size from its image");

    const semantic::MaskResult r = provider->Segment({image, {}});
    const double iou = eval.Add(r.labels, labels);
    total_ms.push_back(r.total_ms);
    network_ms.push_back(r.network_ms);
    crf_ms.push_back(r.crf_ms);
    frames.push_back({{"image", stem}, {"movable_iou", iou}, {"ms", r.total_ms}});

    cv::Mat truth_movable(labels.size(), CV_8U, cv::Scalar(0));
    for (int id : args.label_movable) truth_movable.setTo(255, labels == id);
    cv::Mat valid(labels.size(), CV_8U, cv::Scalar(255));
    for (int id : args.label_ignore) valid.setTo(0, labels == id);
    if (!args.out.empty() && cv::countNonZero(truth_movable & valid) > 0) {
      cv::Mat predicted_movable, truth_classes;
      cv::LUT(r.labels, class_movable_lut, predicted_movable);
      cv::LUT(labels, truth_lut, truth_classes);
      const cv::Mat overlay = FrameOverlay(image, r.labels, truth_classes,
                                           predicted_movable & valid, truth_movable & valid, iou);
      Offer({iou, stem, overlay}, true, 3, &best);
      Offer({iou, stem, overlay}, false, 3, &worst);
    }
    progress.Update(i + 1);
  }
  progress.Finish();

  const eval::ErrorStatistics ms = eval::ComputeStatistics(total_ms);
  const double network_median = eval::ComputeStatistics(network_ms).median;
  const double crf_median = eval::ComputeStatistics(crf_ms).median;
  nlohmann::json json = eval.ToJson();
  json["model"] = args.model;
  json["provider"] = provider->Describe();
  json["images_folder"] = args.images;
  json["labels_folder"] = args.labels;
  json["grey"] = args.grey;
  json["crf"] = args.crf;
  json["suppress_below"] = args.suppress_below;
  json["movable_bias"] = args.movable_bias.value_or(card.refine.movable_bias);
  json["label_movable"] = args.label_movable;
  json["ms_per_image"] = {{"mean", ms.mean},
                          {"median", ms.median},
                          {"max", ms.max},
                          {"network_median", network_median},
                          {"crf_median", crf_median}};
  json["frames"] = frames;
  PrintScores(eval, provider->Describe(), ms.mean, ms.median);
  std::printf("median network %.1f ms (with upsampling), CRF %.1f ms\n", network_median,
              crf_median);
  if (!args.out.empty()) {
    const fs::path out(args.out);
    fs::create_directories(out);
    WriteImage(out / "confusion.png", weak::RenderConfusion(eval.confusion(), eval.class_names()));
    for (size_t k = 0; k < best.size(); ++k) {
      WriteImage(out / fmt::format("best_{}_{}.png", k + 1, best[k].stem), best[k].overlay);
    }
    for (size_t k = 0; k < worst.size(); ++k) {
      WriteImage(out / fmt::format("worst_{}_{}.png", k + 1, worst[k].stem), worst[k].overlay);
    }
    std::ofstream((out / "seg_eval.json").string()) << json.dump(2) << "\n";
    std::printf("confusion.png, best/worst overlays and seg_eval.json in %s\n", args.out.c_str());
  }
  if (!args.json.empty()) {
    std::ofstream file(args.json);
    if (!(file << json.dump(2) << "\n")) ThrowInFile(args.json, "cannot be written");
  }
}

}  // namespace

void AddSegEvalCommand(CLI::App& app) {
  auto args = std::make_shared<SegEvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "seg-eval",
      "Score a segmentation network against label PNGs (CamVid ids): per-class IoU, mean IoU, "
      "movable IoU/precision/recall, ms per image; JSON, confusion.png and the best and worst "
      "frames' overlays");
  cmd->add_option("--model", args->model,
                  "Segmenter model file (.mnet) or model card (.yaml: torch or ONNX segmentation)")
      ->required();
  cmd->add_option("--images", args->images, "Folder of .png/.jpg images (name order)")->required();
  cmd->add_option("--labels", args->labels, "Folder of 8-bit label PNGs named like the images")
      ->required();
  cmd->add_option("--json", args->json, "Write the scores to this JSON file");
  cmd->add_option("--out", args->out,
                  "Folder for confusion.png, seg_eval.json and best_/worst_<n>_<stem>.png");
  cmd->add_flag("--grey", args->grey, "Convert the images to grey before the network");
  cmd->add_option("--crf", args->crf, "Colour CRF on every class (c) or none")
      ->check(CLI::IsMember({"none", "c"}))
      ->capture_default_str();
  cmd->add_option("--suppress-below", args->suppress_below,
                  "Test-time suppression: a class whose image-level score is below this gets "
                  "probability 0 (the background class never); 0 = off")
      ->check(CLI::Range(0.0, 0.999))
      ->capture_default_str();
  cmd->add_option_function<float>(
         "--movable-bias", [args](float bias) { args->movable_bias = bias; },
         "Added to the movable classes' log-probabilities before the decision and the CRF "
         "(refine.movable_bias; default: the card's, 0 for a bare .mnet); choose it on training "
         "images")
      ->check(CLI::Range(-10.0, 10.0));
  cmd->add_option("--label-movable", args->label_movable, "Label ids that are movable")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--label-names", args->label_names,
                  "Class names of the label ids in id order, matched to the model's classes by "
                  "name (default: CamVid's; e.g. the synthetic generator's classes.txt names)")
      ->delimiter(',');
  cmd->add_option("--label-ignore", args->label_ignore, "Label ids left out of every score")
      ->delimiter(',')
      ->capture_default_str();
  cmd->add_option("--threads", args->threads,
                  "libtorch intra-op threads (on a busy machine use 1, or set "
                  "OMP_WAIT_POLICY=passive: OpenMP threads spin while waiting)")
      ->capture_default_str();
  cmd->add_option("--input-width", args->input_width,
                  "Run a torch network at this input width (pixels) instead of its model's; with "
                  "--input-height (the network is fully convolutional)");
  cmd->add_option("--input-height", args->input_height, "Input height for --input-width (pixels)");
  cmd->add_option("--limit", args->limit, "Evaluate only the first N images (0: all)")
      ->capture_default_str();
  cmd->callback([args] { Run(*args); });
}

}  // namespace moslam::app
