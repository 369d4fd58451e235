// GenerateCues (training.h): class activation maps of the colour and grey classifiers turned into
// seeds, refined with superpixels and fused (Sun, Tai, Gao, Liu, Yeung 2019).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/io/image.h"
#include "moslam/net/model_file.h"
#include "moslam/util/error.h"
#include "moslam/util/progress.h"
#include "moslam/weak/training.h"
#include "moslam/weak/training_loop.h"

namespace moslam::weak {

namespace fs = std::filesystem;

namespace internal {

torch::Tensor AugmentedProbabilities(net::SegmenterNet& net, const cv::Mat& image,
                                     const std::vector<double>& scales, bool flip) {
  return MeanOverViews(
             image, scales, flip, net->parameters().front().device(),
             [&net](const torch::Tensor& input) { return net->forward(input).logits; },
             [](const torch::Tensor& logits) { return torch::softmax(logits, 1); })
      .squeeze(0)
      .to(torch::kCPU, torch::kFloat32)
      .contiguous();
}

}  // namespace internal

namespace {

struct CueModel {
  net::ClassifierNet net{nullptr};
  std::string name;  // "colour" or "grey"
};

// The list whose classes the classifiers were trained on: the training list itself, or, when it
// was restricted with keep_classes, possibly the unrestricted list (classifiers trained on every
// class localize better, since the other classes explain the rest of the image; their seeds are
// then merged into the kept classes and the background, see SeedMapping).
ImageList ClassifierList(const CueGenerationOptions& options, const ImageList& list,
                         const std::vector<std::string>& classifier_classes) {
  if (classifier_classes == list.class_names || options.data.keep_classes.empty()) return list;
  DataSource full = options.data;
  full.keep_classes.clear();
  ImageList all = full.Load();
  all.entries.resize(list.entries.size());
  return all;
}

std::vector<CueModel> LoadModels(const CueGenerationOptions& options, const ImageList& list) {
  std::vector<CueModel> models;
  for (const auto& [path, name] :
       {std::pair{options.colour_model, "colour"}, std::pair{options.grey_model, "grey"}}) {
    if (path.empty()) continue;
    CueModel model{net::LoadClassifier(path), name};
    if (!models.empty() && model.net->config().classes != models[0].net->config().classes) {
      throw InputError(
          fmt::format("the colour and grey classifiers have different classes: [{}] "
                      "and [{}]",
                      fmt::join(models[0].net->config().classes, ", "),
                      fmt::join(model.net->config().classes, ", ")));
    }
    if (model.net->config().classes != list.class_names) {
      throw InputError(fmt::format("{} classifier {} has classes [{}], the data has [{}]", name,
                                   path, fmt::join(model.net->config().classes, ", "),
                                   fmt::join(list.class_names, ", ")));
    }
    model.net->eval();
    models.push_back(std::move(model));
  }
  if (models.empty()) throw InputError("cues: give --colour-model and/or --grey-model");
  return models;
}

// Seed value of the classifier's list (class index, or num_classes for its background) ->
// segmenter class index: by name, and every class the segmenter does not have is background.
std::vector<uint8_t> SeedMapping(const ImageList& from, const std::vector<std::string>& seg) {
  const auto background = std::find(seg.begin(), seg.end(), "background");
  const int seg_background =
      background == seg.end() ? kUnknown : static_cast<int>(background - seg.begin());
  std::vector<uint8_t> mapping(256, kUnknown);
  for (int c = 0; c < from.num_classes(); ++c) {
    const auto it = std::find(seg.begin(), seg.end(), from.class_names[c]);
    mapping[c] = it != seg.end() ? static_cast<uint8_t>(it - seg.begin()) : seg_background;
  }
  if (!from.background.empty()) mapping[from.num_classes()] = seg_background;
  return mapping;
}

// Per cell of the label grid: whether its labels list a movable class of `list`.
std::vector<bool> MovableCells(const ImageList& list,
                               const std::vector<std::vector<int>>& cell_classes) {
  std::vector<bool> movable;
  for (const std::vector<int>& classes : cell_classes) {
    movable.push_back(std::any_of(classes.begin(), classes.end(),
                                  [&](int c) { return static_cast<bool>(list.movable[c]); }));
  }
  return movable;
}

cv::Mat MapSeeds(const cv::Mat& seeds, const std::vector<uint8_t>& mapping) {
  cv::Mat out;
  cv::LUT(seeds, mapping, out);
  return out;
}

// Label id -> segmenter class index (-1: not counted) for reporting the cues' precision: CamVid
// ids are the class indices; synthetic ids are mapped by name through its classes.txt.
std::vector<int> EvalMapping(const CueGenerationOptions& options,
                             const std::vector<std::string>& seg_classes) {
  std::vector<std::string> id_names;  // label id -> class name in the label images
  if (!options.data.camvid.empty()) {
    id_names = ReadCamVid(options.data.camvid, options.data.split).class_names;
  } else if (!options.data.synthetic.empty()) {
    const ImageList classes = ReadClassesFile(options.data.synthetic + "/classes.txt");
    id_names = classes.class_names;
    // ReadClassesFile keeps the background out of the labels; its id is 0 in the generator.
    if (!classes.background.empty()) id_names.insert(id_names.begin(), classes.background);
  } else {
    return {};
  }
  // Names not among the segmenter's classes are the background (KeepClasses merged them).
  const auto background = std::find(seg_classes.begin(), seg_classes.end(), "background");
  std::vector<int> mapping(256, -1);
  for (size_t id = 0; id < id_names.size(); ++id) {
    const auto it = std::find(seg_classes.begin(), seg_classes.end(), id_names[id]);
    if (it != seg_classes.end()) {
      mapping[id] = static_cast<int>(it - seg_classes.begin());
    } else if (background != seg_classes.end()) {
      mapping[id] = static_cast<int>(background - seg_classes.begin());
    }
  }
  return mapping;
}

// The classifier has no background output; SeedsFromCams takes the background as one more
// (ignored) plane, so that background seeds carry the segmenter's background index.
cv::Mat WithBackgroundPlane(const cv::Mat& cams, int background) {
  if (background < 0) return cams;
  const int sizes[] = {cams.size[0] + 1, cams.size[1], cams.size[2]};
  cv::Mat out(3, sizes, CV_32F, cv::Scalar(0));
  std::memcpy(out.data, cams.data, cams.total() * sizeof(float));
  return out;
}

struct CueStats {
  double pixels = 0, seeded = 0, correct = 0, labelled_seeded = 0;
  std::map<int, double> per_class_seeded, per_class_correct;
  // Per labelled class: its pixels, and how many of them were seeded as each class (the recall
  // of a class, and which wrong label takes its pixels).
  std::map<int, double> per_class_labelled;
  std::map<int, std::map<int, double>> per_class_seeded_as;
};

void AddEvaluation(const cv::Mat& cue, const cv::Mat& labels, const std::vector<int>& mapping,
                   CueStats* stats) {
  for (int y = 0; y < cue.rows; ++y) {
    for (int x = 0; x < cue.cols; ++x) {
      const int c = cue.at<uint8_t>(y, x);
      const int truth = mapping[labels.at<uint8_t>(y, x)];
      if (truth < 0) continue;
      stats->per_class_labelled[truth] += 1;
      if (c == kUnknown) continue;
      stats->per_class_seeded_as[truth][c] += 1;
      stats->labelled_seeded += 1;
      stats->per_class_seeded[c] += 1;
      if (truth == c) {
        stats->correct += 1;
        stats->per_class_correct[c] += 1;
      }
    }
  }
}

// Writes the cue maps (at each image's original size), gathers their statistics (and, with
// evaluation labels, their precision) and writes cues.json at the end: shared by both rounds.
class CueWriter {
 public:
  CueWriter(const CueGenerationOptions& options, const ImageList& list,
            std::vector<std::string> seg_classes)
      : options_(options),
        list_(list),
        seg_classes_(std::move(seg_classes)),
        cue_folder_((fs::path(options.out) / "cues").string()),
        preview_folder_((fs::path(options.out) / "preview").string()),
        mapping_(options.eval_labels.empty() ? std::vector<int>{}
                                             : EvalMapping(options, seg_classes_)),
        class_pixels_(seg_classes_.size(), 0.0) {
    internal::MakeFolder(cue_folder_);
    internal::MakeFolder(preview_folder_);
  }

  // `cue` at the network's input size (or already at the image's); written at entry i's original
  // size.
  void Write(size_t i, const cv::Mat& cue_in) {
    const cv::Mat original = cv::imread(list_.entries[i].image, cv::IMREAD_UNCHANGED);
    if (original.empty()) throw InputError("cannot read " + list_.entries[i].image);
    cv::Mat cue = cue_in;
    if (cue.size() != original.size()) {
      cv::resize(cue_in, cue, original.size(), 0, 0, cv::INTER_NEAREST);
    }
    cv::imwrite(fmt::format("{}/{:06d}.png", cue_folder_, i), cue);
    stats_.pixels += cue.total();
    for (int y = 0; y < cue.rows; ++y) {
      for (int x = 0; x < cue.cols; ++x) {
        const int c = cue.at<uint8_t>(y, x);
        if (c != kUnknown) {
          stats_.seeded += 1;
          class_pixels_[c] += 1;
        }
      }
    }
    if (!mapping_.empty()) {
      const std::string label_path =
          (fs::path(options_.eval_labels) / fs::path(list_.entries[i].image).stem()).string() +
          ".png";
      const cv::Mat labels = cv::imread(label_path, cv::IMREAD_GRAYSCALE);
      if (labels.size() == cue.size()) AddEvaluation(cue, labels, mapping_, &stats_);
    }
  }

  void WritePreview(size_t i, const std::vector<cv::Mat>& panels,
                    const std::vector<std::string>& captions) const {
    cv::imwrite(fmt::format("{}/cues_{:04d}.png", preview_folder_, i),
                internal::SideBySide(panels, captions));
  }

  void Finish(const std::vector<std::string>& models) const {
    nlohmann::json report = {
        {"classes", seg_classes_},
        {"images", list_.entries.size()},
        {"models", models},
        {"seeded_fraction", stats_.seeded / std::max(1.0, stats_.pixels)},
        {"label_grid", {options_.label_grid_cols, options_.label_grid_rows}},
        {"cell_max", options_.cell_max},
        {"no_background_in_movable_cells", options_.no_background_in_movable_cells},
        {"scales", options_.scales},
        {"flip", options_.flip}};
    if (!options_.segmenter_model.empty()) {
      report["self_training"] = {{"confidence", options_.confidence},
                                 {"fallback_cues", options_.fallback_cues},
                                 {"fallback_per_class", options_.fallback_per_class},
                                 {"depth_folder", options_.depth_folder}};
    }
    for (size_t c = 0; c < seg_classes_.size(); ++c) {
      report["class_fraction"][seg_classes_[c]] = class_pixels_[c] / std::max(1.0, stats_.pixels);
    }
    if (stats_.labelled_seeded > 0) {
      report["precision"] = stats_.correct / stats_.labelled_seeded;
      for (const auto& [c, n] : stats_.per_class_seeded) {
        report["class_precision"][seg_classes_[c]] = stats_.per_class_correct.at(c) / n;
      }
      spdlog::info("cues: {:.1f} % of pixels seeded, precision {:.3f} against the pixel labels",
                   100.0 * stats_.seeded / stats_.pixels, stats_.correct / stats_.labelled_seeded);
      for (const auto& [c, n] : stats_.per_class_seeded) {
        spdlog::info("cues: {} seeded on {:.1f} % of pixels, precision {:.3f}", seg_classes_[c],
                     100.0 * class_pixels_[c] / std::max(1.0, stats_.pixels),
                     stats_.per_class_correct.at(c) / n);
      }
      for (const auto& [truth, n] : stats_.per_class_labelled) {
        const auto it = stats_.per_class_seeded_as.find(truth);
        std::string as;
        for (size_t c = 0; c < seg_classes_.size(); ++c) {
          const double k = it == stats_.per_class_seeded_as.end() || !it->second.count(c)
                               ? 0.0
                               : it->second.at(c);
          report["class_seeded_as"][seg_classes_[truth]][seg_classes_[c]] = k / n;
          as += fmt::format(" {} {:.3f}", seg_classes_[c], k / n);
        }
        spdlog::info("cues: {} pixels ({:.1f} % of all) seeded as:{}", seg_classes_[truth],
                     100.0 * n / std::max(1.0, stats_.pixels), as);
      }
    }
    std::ofstream(fs::path(options_.out) / "cues.json") << report.dump(2) << "\n";
  }

 private:
  const CueGenerationOptions& options_;
  const ImageList& list_;
  const std::vector<std::string> seg_classes_;
  const std::string cue_folder_, preview_folder_;
  const std::vector<int> mapping_;
  CueStats stats_;
  std::vector<double> class_pixels_;
};

ImageList TrainingList(const CueGenerationOptions& options) {
  ImageList list = options.data.Load();
  if (options.max_images > 0 && static_cast<int>(list.entries.size()) > options.max_images) {
    list.entries.resize(options.max_images);
  }
  return list;
}

// Cue `index` of `folder` as stored (at the image's original size, so CueWriter::Write keeps it
// as it is), or all kUnknown of `size` without a folder.
cv::Mat FallbackCue(const std::string& folder, size_t index, cv::Size size) {
  if (folder.empty()) return cv::Mat(size, CV_8UC1, cv::Scalar(kUnknown));
  const std::string path = fmt::format("{}/cues/{:06d}.png", folder, index);
  const cv::Mat cue = cv::imread(path, cv::IMREAD_UNCHANGED);
  if (cue.empty() || cue.type() != CV_8UC1) {
    throw InputError("cues: fallback cue " + path + " is missing or not an 8-bit label image");
  }
  return cue;
}

// The image's depth (CueGenerationOptions::depth_folder) in metres at `size` (the cue's, which
// is the network input's): nearest neighbour, so no reading is averaged across a depth edge or
// with a hole.
cv::Mat DepthOf(const ImageListEntry& entry, const CueGenerationOptions& options, cv::Size size) {
  const std::string path =
      (fs::path(options.depth_folder) / fs::path(entry.image).filename()).string();
  if (!fs::exists(path)) {
    throw InputError(fmt::format("cues: no depth image {} for {} (--depth-folder {})", path,
                                 entry.image, options.depth_folder));
  }
  const cv::Mat depth = io::LoadDepthImage(path, options.depth_factor);
  cv::Mat resized;
  cv::resize(depth, resized, size, 0, 0, cv::INTER_NEAREST);
  return resized;
}

// The second round (CueGenerationOptions::segmenter_model): cues from a trained segmenter.
void GenerateCuesFromSegmenter(const CueGenerationOptions& options) {
  if (!options.depth_folder.empty() && !(options.depth_factor > 0.0)) {
    throw InputError(fmt::format("cues: depth_factor must be > 0 (raw units per metre), got {}",
                                 options.depth_factor));
  }
  if (options.fallback_per_class && options.fallback_cues.empty()) {
    throw InputError("cues: fallback_per_class (--fallback-per-class) needs fallback cues");
  }
  if (!(options.min_class_pixels >= 0.0f && options.min_class_pixels < 1.0f)) {
    throw InputError(
        fmt::format("cues: min_class_pixels must be in [0, 1), got {}", options.min_class_pixels));
  }
  const ImageList list = TrainingList(options);
  const std::vector<std::string> seg_classes = SegmenterClasses(list);
  net::SegmenterNet net = net::LoadSegmenter(options.segmenter_model);
  if (net->config().classes != seg_classes) {
    throw InputError(fmt::format("cues: segmenter {} has classes [{}], the data has [{}]",
                                 options.segmenter_model, fmt::join(net->config().classes, ", "),
                                 fmt::join(seg_classes, ", ")));
  }
  net->eval();
  torch::NoGradGuard no_grad;
  const int background = net->config().BackgroundIndex();
  AugmentOptions resize;
  resize.output_width = net->config().input_width;
  resize.output_height = net->config().input_height;
  resize.label_grid_cols = options.label_grid_cols;
  resize.label_grid_rows = options.label_grid_rows;
  resize.Check();
  RequireLabelImages(list, resize, "cues");
  semantic::DenseCrfOptions crf_options = options.crf;
  crf_options.depth = !options.depth_folder.empty();
  crf_options.num_threads = std::max(1, options.threads);
  semantic::DenseCrf crf(crf_options);
  CueWriter writer(options, list, seg_classes);
  Progress progress("cues", list.entries.size(), 10.0, "img");
  std::mt19937_64 rng(1);
  size_t missed = 0;
  for (size_t i = 0; i < list.entries.size(); ++i) {
    const Sample sample = LoadSample(list, static_cast<int>(i), resize, rng, false);
    const torch::Tensor probabilities =
        internal::AugmentedProbabilities(net, sample.image, options.scales, options.flip);
    const int sizes[] = {static_cast<int>(probabilities.size(0)), sample.image.rows,
                         sample.image.cols};
    cv::Mat planar(3, sizes, CV_32F, probabilities.data_ptr<float>());
    if (options.label_grid_cols > 0) {
      // The background is in every cell: only the listed classes are removed where absent.
      std::vector<std::vector<int>> cell_classes = sample.cell_classes;
      for (std::vector<int>& classes : cell_classes) classes.push_back(background);
      SuppressAbsentInCells(planar, cell_classes, options.label_grid_rows, options.label_grid_cols);
    }
    const cv::Mat depth_m = options.depth_folder.empty()
                                ? cv::Mat()
                                : DepthOf(list.entries[i], options, sample.image.size());
    cv::Mat cue = CuesFromSegmentation(planar, sample.classes, background, sample.image, depth_m,
                                       crf, options.confidence);
    if (options.no_background_in_movable_cells) {
      ClearLabelInCells(cue, MovableCells(list, sample.cell_classes), options.label_grid_rows,
                        options.label_grid_cols, background);
    }
    const std::vector<int> missed_classes =
        MissedClasses(cue, sample.classes, background, options.min_class_pixels);
    if (!missed_classes.empty()) {
      ++missed;
      if (options.fallback_per_class) {
        FillClassesFrom(FallbackCue(options.fallback_cues, i, cue.size()), missed_classes, cue);
      } else {
        cue = FallbackCue(options.fallback_cues, i, cue.size());
      }
    }
    writer.Write(i, cue);
    if (static_cast<int>(i) < options.preview_images) {
      const torch::Tensor labels = probabilities.argmax(0).to(torch::kUInt8).contiguous();
      const cv::Mat argmax(sample.image.size(), CV_8UC1, labels.data_ptr<uint8_t>());
      cv::Mat shown;
      cv::resize(cue, shown, sample.image.size(), 0, 0, cv::INTER_NEAREST);
      writer.WritePreview(
          i, {sample.image, RenderCue(argmax, sample.image), RenderCue(shown, sample.image)},
          {"image", "segmenter", "CRF cue"});
    }
    progress.Update(i + 1);
  }
  progress.Finish();
  spdlog::info("cues: the segmenter missed a labelled class in {} of {} images ({})", missed,
               list.entries.size(),
               options.fallback_cues.empty() ? "left without cues"
               : options.fallback_per_class
                   ? "the missed classes' first-round seeds put into the segmenter's cue"
                   : "first-round cues used");
  writer.Finish({options.segmenter_model});
}

}  // namespace

void GenerateCues(const CueGenerationOptions& options) {
  options.data.Check();
  options.cues.Check();
  if (options.scales.empty()) throw InputError("cues: scales must not be empty");
  for (double scale : options.scales) {
    if (!(scale >= 0.25 && scale <= 4.0)) {
      throw InputError(fmt::format("cues: scales must be in [0.25, 4], got {}", scale));
    }
  }
  at::set_num_threads(options.threads);
  if ((options.cell_max || options.no_background_in_movable_cells) &&
      options.label_grid_cols == 0) {
    throw InputError("cues: --cell-max and --no-background-in-movable-cells need a label grid");
  }
  if (!options.segmenter_model.empty()) {
    if (!options.colour_model.empty() || !options.grey_model.empty()) {
      throw InputError("cues: give either --segmenter or classifier models, not both");
    }
    if (options.cell_max) throw InputError("cues: --cell-max is for classifier cues only");
    GenerateCuesFromSegmenter(options);
    return;
  }
  if (!options.depth_folder.empty()) {
    throw InputError("cues: --depth-folder is for self-training cues (--segmenter) only");
  }
  const ImageList list = TrainingList(options);
  const std::vector<std::string> classifier_classes =
      net::ReadNetConfig(options.colour_model.empty() ? options.grey_model : options.colour_model)
          .classes;
  const ImageList cam_list = ClassifierList(options, list, classifier_classes);
  std::vector<CueModel> models = LoadModels(options, cam_list);
  const std::vector<std::string> seg_classes = SegmenterClasses(list);
  const std::vector<uint8_t> to_seg = SeedMapping(cam_list, seg_classes);
  const int background = cam_list.background.empty() ? -1 : cam_list.num_classes();
  // SegmenterClasses: the list's classes, then its background when it has one.
  const int seg_background = list.background.empty() ? -1 : list.num_classes();
  if (options.no_background_in_movable_cells && seg_background < 0) {
    throw InputError("cues: --no-background-in-movable-cells needs a background class");
  }
  const net::NetConfig& config = models[0].net->config();
  AugmentOptions resize;
  resize.output_width = config.input_width;
  resize.output_height = config.input_height;
  resize.label_grid_cols = options.label_grid_cols;
  resize.label_grid_rows = options.label_grid_rows;
  resize.Check();
  RequireLabelImages(cam_list, resize, "cues");
  CueWriter writer(options, list, seg_classes);
  Progress progress("cues", list.entries.size(), 10.0, "img");
  std::mt19937_64 rng(1);
  for (size_t i = 0; i < list.entries.size(); ++i) {
    const Sample sample = LoadSample(cam_list, static_cast<int>(i), resize, rng, false);
    std::vector<cv::Mat> refined, panels = {sample.image};
    std::vector<std::string> captions = {"image"};
    for (CueModel& model : models) {
      cv::Mat input = sample.image;
      if (model.net->config().grey) {
        cv::Mat grey;
        cv::cvtColor(sample.image, grey, cv::COLOR_BGR2GRAY);
        cv::cvtColor(grey, input, cv::COLOR_GRAY2BGR);
      }
      cv::Mat cams = internal::AugmentedCams(model.net, input, options.scales, options.flip);
      if (options.label_grid_cols > 0) {
        SuppressAbsentInCells(cams, sample.cell_classes, options.label_grid_rows,
                              options.label_grid_cols, options.cell_max);
      }
      cv::Mat seeds = MapSeeds(SeedsFromCams(WithBackgroundPlane(cams, background), sample.classes,
                                             background, options.cues),
                               to_seg);
      if (options.no_background_in_movable_cells) {
        ClearLabelInCells(seeds, MovableCells(cam_list, sample.cell_classes),
                          options.label_grid_rows, options.label_grid_cols, seg_background);
      }
      refined.push_back(RefineWithSuperpixels(seeds, input, options.cues));
      if (static_cast<int>(i) < options.preview_images) {
        for (int c : sample.classes) {
          if (cam_list.movable[c]) {
            panels.push_back(RenderCam(semantic::LabelPlane(cams, c), input));
            captions.push_back(model.name + " CAM " + cam_list.class_names[c]);
          }
        }
        panels.push_back(RenderCue(seeds, input));
        captions.push_back(model.name + " seeds");
        panels.push_back(RenderCue(refined.back(), input));
        captions.push_back(model.name + " superpixels");
      }
    }
    const cv::Mat fused =
        refined.size() == 2 ? FuseCues(refined[0], refined[1], options.fuse_one_sided) : refined[0];
    writer.Write(i, fused);
    if (static_cast<int>(i) < options.preview_images) {
      panels.push_back(RenderCue(fused, sample.image));
      captions.push_back("fused");
      writer.WritePreview(i, panels, captions);
    }
    progress.Update(i + 1);
  }
  progress.Finish();
  writer.Finish({options.colour_model, options.grey_model});
}

}  // namespace moslam::weak
