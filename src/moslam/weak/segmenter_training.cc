// TrainSegmenter (training.h): the segmentation network trained on fused cues with the seeding
// and constrain-to-boundary losses of SEC (Kolesnikov and Lampert 2016), as Sun et al. 2019 do.
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/net/model_file.h"
#include "moslam/util/error.h"
#include "moslam/weak/losses.h"
#include "moslam/weak/training.h"
#include "moslam/weak/training_loop.h"

namespace moslam::weak {

namespace fs = std::filesystem;

namespace {

std::string CuePath(const std::string& folder, int index) {
  return fmt::format("{}/cues/{:06d}.png", folder, index);
}

void CheckCues(const SegmenterTrainOptions& options, const ImageList& list) {
  const fs::path report = fs::path(options.cues) / "cues.json";
  if (!fs::exists(report)) {
    throw InputError("segmenter: " + report.string() + " not found (run `moslam train cues`)");
  }
  const nlohmann::json cues = nlohmann::json::parse(std::ifstream(report));
  const auto classes = cues.at("classes").get<std::vector<std::string>>();
  if (classes != SegmenterClasses(list)) {
    throw InputError(fmt::format("segmenter: cues in {} are for classes [{}], the data has [{}]",
                                 options.cues, fmt::join(classes, ", "),
                                 fmt::join(SegmenterClasses(list), ", ")));
  }
  if (cues.at("images").get<size_t>() < list.entries.size()) {
    throw InputError(fmt::format("segmenter: {} has cues for {} images, the data has {}",
                                 options.cues, cues.at("images").get<size_t>(),
                                 list.entries.size()));
  }
}

// Copies the backbone weights of a trained classifier (same last block required). The output
// strides may differ: dilation changes no weight's shape, so a classifier trained at stride 8 for
// finer activation maps can start a stride-16 segmenter that meets the inference budget.
void InitFromClassifier(const std::string& path, net::SegmenterNet& net) {
  net::ClassifierNet classifier = net::LoadClassifier(path);
  const auto& a = classifier->config().backbone;
  const auto& b = net->config().backbone;
  if (a.last_block != b.last_block) {
    throw InputError(
        fmt::format("segmenter: classifier {} has backbone last_block {}, the segmenter {}", path,
                    a.last_block, b.last_block));
  }
  if (a.output_stride != b.output_stride) {
    spdlog::info("segmenter: backbone from a stride-{} classifier, trained at stride {}",
                 a.output_stride, b.output_stride);
  }
  torch::NoGradGuard no_grad;
  auto source = classifier->backbone()->named_parameters();
  for (auto& item : net->backbone()->named_parameters()) {
    item.value().copy_(source[item.key()]);
  }
}

net::SegmenterNet BuildSegmenter(const SegmenterTrainOptions& options, const ImageList& list,
                                 CommonTrainOptions* common) {
  net::NetConfig config = options.net;
  config.kind = net::NetKind::kSegmenter;
  config.classes = SegmenterClasses(list);
  config.background = list.background;
  config.movable.clear();
  for (int c = 0; c < list.num_classes(); ++c) {
    if (list.movable[c]) config.movable.push_back(list.class_names[c]);
  }
  config.input_width = common->augment.output_width;
  config.input_height = common->augment.output_height;
  config.grey = false;
  common->augment.grey = false;
  config.Check();
  net::SegmenterNet net(config);
  if (!options.init_classifier.empty()) {
    InitFromClassifier(options.init_classifier, net);
  } else if (options.imagenet_weights != "none") {
    net::LoadImageNetWeights(options.imagenet_weights.empty() ? net::DefaultImageNetWeightsPath()
                                                              : options.imagenet_weights,
                             net->backbone());
  }
  net->backbone()->ApplyFreezing();
  return net;
}

semantic::DenseCrfOptions ScaledCrf(semantic::DenseCrfOptions crf, double factor) {
  crf.smoothness_sxy = std::max(0.5f, static_cast<float>(crf.smoothness_sxy / factor));
  crf.appearance_sxy = std::max(0.5f, static_cast<float>(crf.appearance_sxy / factor));
  crf.depth_sxy = std::max(0.5f, static_cast<float>(crf.depth_sxy / factor));
  crf.depth = false;
  crf.num_threads = 1;
  crf.Check();
  return crf;
}

// The logits the losses see: the network's, or bilinearly upsampled to input / loss_stride
// (training.h, SegmenterTrainOptions::loss_stride).
torch::Tensor LossLogits(const torch::Tensor& logits, const torch::Tensor& images,
                         int loss_stride) {
  if (loss_stride <= 0) return logits;
  const int64_t h = std::max<int64_t>(1, images.size(2) / loss_stride);
  const int64_t w = std::max<int64_t>(1, images.size(3) / loss_stride);
  if (h <= logits.size(2) && w <= logits.size(3)) return logits;
  return net::UpsampleBilinear(logits, h, w);
}

cv::Mat LabelsToMat(const torch::Tensor& labels) {
  const torch::Tensor l = labels.to(torch::kUInt8).contiguous();
  cv::Mat out(static_cast<int>(l.size(0)), static_cast<int>(l.size(1)), CV_8U);
  std::memcpy(out.data, l.data_ptr<uint8_t>(), l.numel());
  return out;
}

void WritePreviews(net::SegmenterNet& net, const ImageList& list,
                   const SegmenterTrainOptions& options, const AugmentOptions& resize) {
  const std::string folder = (fs::path(options.common.out) / "preview").string();
  internal::MakeFolder(folder);
  net->eval();
  torch::NoGradGuard no_grad;
  std::mt19937_64 rng(options.common.seed);
  const int count = std::min<int>(options.common.preview_images, list.entries.size());
  for (int i = 0; i < count; ++i) {
    const Sample s = LoadSample(list, i, resize, rng, false, CuePath(options.cues, i));
    const torch::Device device = net->parameters().front().device();
    const torch::Tensor logits =
        net->forward(ToInputTensor(s.image).unsqueeze(0).to(device)).logits.to(torch::kCPU);
    const torch::Tensor up = net::UpsampleBilinear(logits, s.image.rows, s.image.cols);
    const cv::Mat prediction = LabelsToMat(up.squeeze(0).argmax(0));
    cv::imwrite(
        fmt::format("{}/seg_{:04d}.png", folder, i),
        internal::SideBySide({s.image, RenderCue(s.cue, s.image), RenderCue(prediction, s.image)},
                             {"image", "fused cue", "prediction"}));
  }
}

}  // namespace

TrainSummary TrainSegmenter(const SegmenterTrainOptions& options_in) {
  SegmenterTrainOptions options = options_in;
  CommonTrainOptions& common = options.common;
  common.Check();
  if (options.cues.empty()) throw InputError("segmenter: --cues (a cue folder) is required");
  if (options.grey_probability < 0 || options.grey_probability > 1) {
    throw InputError("segmenter: grey_probability must be in [0, 1]");
  }
  if (options.loss_stride < 0) {
    throw InputError(
        fmt::format("segmenter: loss_stride must be >= 0, got {}", options.loss_stride));
  }
  at::set_num_threads(common.threads);
  torch::manual_seed(common.seed);
  const ImageList list = internal::LoadTrainingList(common);
  CheckCues(options, list);
  net::SegmenterNet net = BuildSegmenter(options, list, &common);
  const torch::Device device = internal::TrainingDevice();
  net->to(device);
  const int num_classes = net->config().num_classes();
  const int background = net->config().BackgroundIndex();
  auto optimizer = internal::MakeOptimizer(*net->backbone(), *net, common);
  std::unique_ptr<semantic::DenseCrf> crf;
  spdlog::info("segmenter: {} images, classes [{}], input {}x{}, {} epochs of batch {}",
               list.entries.size(), fmt::join(net->config().classes, ", "),
               net->config().input_width, net->config().input_height, common.epochs,
               common.batch_size);

  internal::LoopSpec spec;
  spec.name = "segmenter";
  spec.num_images = static_cast<int>(list.entries.size());
  spec.net = net.ptr().get();
  spec.config = &net->config();
  spec.optimizer = optimizer.get();
  spec.step = [&](const std::vector<int>& indices, std::mt19937_64& rng) {
    std::vector<Sample> samples;
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    for (int i : indices) {
      samples.push_back(LoadSample(list, i, common.augment, rng, true, CuePath(options.cues, i)));
      if (uniform(rng) < options.grey_probability) {
        cv::Mat grey;
        cv::cvtColor(samples.back().image, grey, cv::COLOR_BGR2GRAY);
        cv::cvtColor(grey, samples.back().image, cv::COLOR_GRAY2BGR);
      }
    }
    Batch batch = MakeBatch(samples, num_classes);
    if (background >= 0) batch.labels.select(1, background).fill_(1.0);
    const torch::Tensor labels = batch.labels.to(device);
    const net::SegmenterOutput out = net->forward(batch.images.to(device));
    const torch::Tensor logits = LossLogits(out.logits, batch.images, options.loss_stride);
    const int64_t h = logits.size(2), w = logits.size(3);
    if (!crf) {
      crf = std::make_unique<semantic::DenseCrf>(
          ScaledCrf(options.crf, static_cast<double>(batch.images.size(3)) / w));
    }
    const torch::Tensor cues = DownsampleCues(batch.cues, h, w).to(device);
    const torch::Tensor seed = SeedingLoss(logits, cues, options.seed_balance);
    const torch::Tensor constrain = ConstrainLoss(logits, CrfTargets(logits, batch.bgr, *crf));
    const torch::Tensor classes = torch::binary_cross_entropy_with_logits(out.class_logits, labels);
    const torch::Tensor loss =
        seed + options.constrain_weight * constrain + options.class_weight * classes;
    optimizer->zero_grad();
    loss.backward();
    optimizer->step();
    internal::StepStats stats;
    stats.loss = loss.item<double>();
    stats.parts = {{"seed", seed.item<double>()},
                   {"constrain", constrain.item<double>()},
                   {"class", classes.item<double>()}};
    const torch::Tensor seeded = cues.ne(kUnknown);
    stats.correct = (logits.detach().argmax(1).eq(cues) & seeded).sum().item<double>();
    stats.count = seeded.sum().item<double>();
    stats.images = static_cast<int>(indices.size());
    return stats;
  };
  spec.save_model = [&](const std::string& path) { net::SaveSegmenter(path, net, true); };
  const TrainSummary summary = internal::RunTrainingLoop(common, spec);
  AugmentOptions resize = common.augment;
  WritePreviews(net, list, options, resize);
  internal::WriteReport(common, "segmenter", summary, net->config(), list.entries.size(),
                        {{"constrain_weight", options.constrain_weight},
                         {"class_weight", options.class_weight},
                         {"grey_probability", options.grey_probability},
                         {"loss_stride", options.loss_stride},
                         {"seed_balance", options.seed_balance},
                         {"crf_appearance_weight", options.crf.appearance_weight},
                         {"crf_appearance_sxy", options.crf.appearance_sxy},
                         {"crf_smoothness_weight", options.crf.smoothness_weight}});
  return summary;
}

}  // namespace moslam::weak
