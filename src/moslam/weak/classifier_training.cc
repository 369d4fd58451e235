// TrainClassifier (training.h): multi-label classification with class activation maps.
#include <cstring>
#include <filesystem>
#include <fstream>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/net/model_file.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/weak/training.h"
#include "moslam/weak/training_loop.h"

namespace moslam::weak {

namespace fs = std::filesystem;

namespace internal {

namespace {

// {C, H, W} CV_32F copy of a C x H x W CPU float tensor.
cv::Mat PlanarFromTensor(const torch::Tensor& tensor) {
  const torch::Tensor t = tensor.to(torch::kCPU, torch::kFloat32).contiguous();
  const int sizes[] = {static_cast<int>(t.size(0)), static_cast<int>(t.size(1)),
                       static_cast<int>(t.size(2))};
  cv::Mat result(3, sizes, CV_32F);
  std::memcpy(result.data, t.data_ptr<float>(), t.numel() * sizeof(float));
  return result;
}

}  // namespace

cv::Mat ComputeCams(net::ClassifierNet& net, const cv::Mat& image, std::vector<float>* scores) {
  torch::NoGradGuard no_grad;
  const torch::Device device = net->parameters().front().device();
  const torch::Tensor input = ToInputTensor(image).unsqueeze(0).to(device);
  const net::ClassifierOutput out = net->forward(input);
  if (scores) {
    const torch::Tensor s = torch::sigmoid(out.logits.squeeze(0)).to(torch::kCPU).contiguous();
    scores->assign(s.data_ptr<float>(), s.data_ptr<float>() + s.numel());
  }
  return PlanarFromTensor(net::UpsampleBilinear(out.cams, image.rows, image.cols).squeeze(0));
}

cv::Mat AugmentedCams(net::ClassifierNet& net, const cv::Mat& image,
                      const std::vector<double>& scales, bool flip) {
  // ReLU before the mean: a view's negative evidence should not cancel another's positive
  // response (every CAM is ReLU'd before its seeds are taken anyway).
  return PlanarFromTensor(
      MeanOverViews(
          image, scales, flip, net->parameters().front().device(),
          [&net](const torch::Tensor& input) { return net->forward(input).cams; },
          [](const torch::Tensor& cams) { return torch::relu(cams); })
          .squeeze(0));
}

cv::Mat SideBySide(const std::vector<cv::Mat>& panels, const std::vector<std::string>& captions) {
  MOSLAM_CHECK(!panels.empty());
  const int height = panels[0].rows;
  std::vector<cv::Mat> resized;
  for (size_t i = 0; i < panels.size(); ++i) {
    cv::Mat panel = panels[i];
    if (panel.channels() == 1) cv::cvtColor(panel, panel, cv::COLOR_GRAY2BGR);
    if (panel.rows != height) {
      cv::resize(panel, panel, cv::Size(panel.cols * height / panel.rows, height));
    } else {
      panel = panel.clone();
    }
    if (i < captions.size()) {
      cv::putText(panel, captions[i], {6, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0),
                  3, cv::LINE_AA);
      cv::putText(panel, captions[i], {6, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
                  cv::Scalar(255, 255, 255), 1, cv::LINE_AA);
    }
    resized.push_back(panel);
  }
  cv::Mat out;
  cv::hconcat(resized, out);
  return out;
}

}  // namespace internal

namespace {

net::ClassifierNet BuildClassifier(const ClassifierTrainOptions& options, const ImageList& list,
                                   CommonTrainOptions* common) {
  net::NetConfig config = options.net;
  config.kind = net::NetKind::kClassifier;
  config.classes = list.class_names;
  config.movable.clear();
  for (int c = 0; c < list.num_classes(); ++c) {
    if (list.movable[c]) config.movable.push_back(list.class_names[c]);
  }
  config.background.clear();
  config.input_width = common->augment.output_width;
  config.input_height = common->augment.output_height;
  common->augment.grey = config.grey;
  config.Check();
  net::ClassifierNet net(config);
  if (options.imagenet_weights != "none") {
    const std::string path = options.imagenet_weights.empty() ? net::DefaultImageNetWeightsPath()
                                                              : options.imagenet_weights;
    net::LoadImageNetWeights(path, net->backbone());
    net->backbone()->ApplyFreezing();
  }
  return net;
}

void WritePreviews(net::ClassifierNet& net, const ImageList& list,
                   const CommonTrainOptions& options) {
  const std::string folder = (fs::path(options.out) / "preview").string();
  internal::MakeFolder(folder);
  net->eval();
  std::mt19937_64 rng(options.seed);
  const int count = std::min<int>(options.preview_images, list.entries.size());
  for (int i = 0; i < count; ++i) {
    const Sample sample = LoadSample(list, i, options.augment, rng, /*augment=*/false);
    std::vector<float> scores;
    const cv::Mat cams = internal::ComputeCams(net, sample.image, &scores);
    std::vector<cv::Mat> panels = {sample.image};
    std::vector<std::string> captions = {"image"};
    for (int c : sample.classes) {
      panels.push_back(RenderCam(semantic::LabelPlane(cams, c), sample.image));
      captions.push_back(fmt::format("{} {:.2f}", list.class_names[c], scores[c]));
    }
    cv::imwrite(fmt::format("{}/cam_{:04d}.png", folder, i),
                internal::SideBySide(panels, captions));
  }
}

}  // namespace

TrainSummary TrainClassifier(const ClassifierTrainOptions& options_in) {
  ClassifierTrainOptions options = options_in;
  CommonTrainOptions& common = options.common;
  common.Check();
  at::set_num_threads(common.threads);
  torch::manual_seed(common.seed);
  const ImageList list = internal::LoadTrainingList(common);
  const int grid_rows = common.augment.label_grid_rows;
  const int grid_cols = common.augment.label_grid_cols;
  RequireLabelImages(list, common.augment, "train classifier");
  net::ClassifierNet net = BuildClassifier(options, list, &common);
  const torch::Device device = internal::TrainingDevice();
  net->to(device);
  auto optimizer = internal::MakeOptimizer(*net->backbone(), *net, common);
  spdlog::info("classifier ({}): {} images, {} classes, input {}x{}, {} epochs of batch {}",
               net->config().grey ? "grey" : "colour", list.entries.size(), list.num_classes(),
               net->config().input_width, net->config().input_height, common.epochs,
               common.batch_size);

  internal::LoopSpec spec;
  spec.name = net->config().grey ? "classifier (grey)" : "classifier (colour)";
  spec.num_images = static_cast<int>(list.entries.size());
  spec.net = net.ptr().get();
  spec.config = &net->config();
  spec.optimizer = optimizer.get();
  spec.step = [&](const std::vector<int>& indices, std::mt19937_64& rng) {
    std::vector<Sample> samples;
    for (int i : indices) samples.push_back(LoadSample(list, i, common.augment, rng, true));
    const Batch batch = MakeBatch(samples, list.num_classes(), grid_rows, grid_cols);
    const torch::Tensor labels = batch.labels.to(device);
    const net::ClassifierOutput out = net->forward(batch.images.to(device));
    torch::Tensor loss = torch::binary_cross_entropy_with_logits(out.logits, labels);
    if (grid_cols > 0) {
      // Each cell is a crop labelled by what it contains: its logit is the CAM's mean over the
      // cell, as the image's logit is the CAM's mean over the image (ClassifierNet).
      const torch::Tensor cell_logits =
          torch::adaptive_avg_pool2d(out.cams, {grid_rows, grid_cols});
      loss =
          loss + torch::binary_cross_entropy_with_logits(cell_logits, batch.cell_labels.to(device));
    }
    optimizer->zero_grad();
    loss.backward();
    optimizer->step();
    internal::StepStats stats;
    stats.loss = loss.item<double>();
    const torch::Tensor predicted = (out.logits.detach() > 0).to(torch::kFloat);
    stats.correct = predicted.eq(labels).sum().item<double>();
    stats.count = static_cast<double>(labels.numel());
    stats.images = static_cast<int>(indices.size());
    return stats;
  };
  spec.save_model = [&](const std::string& path) { net::SaveClassifier(path, net); };
  const TrainSummary summary = internal::RunTrainingLoop(common, spec);
  WritePreviews(net, list, common);
  internal::WriteReport(common, "classifier", summary, net->config(), list.entries.size(),
                        {{"label_grid", {grid_cols, grid_rows}}});
  return summary;
}

}  // namespace moslam::weak
