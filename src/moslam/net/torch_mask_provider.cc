#include "moslam/net/torch_mask_provider.h"

#include <chrono>
#include <cmath>
#include <filesystem>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <opencv2/imgproc.hpp>

#include "moslam/net/model_file.h"
#include "moslam/net/torch_segmenter.h"
#include "moslam/util/error.h"

namespace moslam::net {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

const semantic::ModelCard& RequireTorch(const semantic::ModelCard& card) {
  if (card.kind != semantic::ModelKind::kTorch) {
    ThrowInFile(card.path, fmt::format("type: is {}, the libtorch provider needs a torch card",
                                       semantic::ToString(card.kind)));
  }
  return card;
}

semantic::ModelCard Completed(semantic::ModelCard card, const NetConfig& config) {
  CompleteTorchCard(config, &card);
  return card;
}

bool Near(double a, double b) { return std::abs(a - b) <= 1e-6 * std::abs(b); }

}  // namespace

void CompleteTorchCard(const NetConfig& config, semantic::ModelCard* card) {
  RequireTorch(*card);
  if (config.kind != NetKind::kSegmenter) {
    ThrowInFile(card->model,
                fmt::format("is a classifier; the torch card {} needs a segmenter", card->path));
  }
  if (card->classes.empty()) {
    card->classes = config.classes;
  } else if (card->classes != config.classes) {
    ThrowInFile(card->path, fmt::format("classes: [{}] are not the model's [{}] (omit the key to "
                                        "take them from {})",
                                        fmt::join(card->classes, ", "),
                                        fmt::join(config.classes, ", "), card->model));
  }
  if (card->movable.empty()) card->movable = config.movable;
  if (card->background.empty()) {
    card->background = config.background;
  } else if (card->background != config.background) {
    ThrowInFile(card->path, fmt::format("background: '{}' is not the model's ('{}')",
                                        card->background, config.background));
  }
  if (card->input_width == 0 && card->input_height == 0) {
    card->input_width = config.input_width;
    card->input_height = config.input_height;
  } else if (card->input_width < kMinInputSide || card->input_height < kMinInputSide) {
    // The network is fully convolutional: a card may run it at another size than it was trained
    // at (TorchSegmenter::set_input_size), but not below its smallest useful input.
    ThrowInFile(card->path, fmt::format("input_width, input_height: {}x{}, a torch model needs at "
                                        "least {}x{} (omit them to take the model's {}x{})",
                                        card->input_width, card->input_height, kMinInputSide,
                                        kMinInputSide, config.input_width, config.input_height));
  }
  // ImageToTensor (networks.h) feeds RGB scaled to [-1, 1]; a card cannot change that.
  if (card->mean.size() != 3 || !Near(card->mean[0], 127.5) || !Near(card->mean[1], 127.5) ||
      !Near(card->mean[2], 127.5) || !Near(card->scale, 1.0 / 127.5) || !card->rgb) {
    ThrowInFile(card->path,
                "mean, scale, rgb: a torch model takes RGB in [-1, 1] (mean 127.5, scale "
                "1/127.5, rgb true); omit these keys");
  }
  card->Check();
}

void CompleteTorchCard(semantic::ModelCard* card) {
  RequireTorch(*card);
  CompleteTorchCard(ReadNetConfig(card->model), card);
}

semantic::ModelCard TorchModelCard(const std::string& model_path) {
  semantic::ModelCard card;
  card.path = model_path;
  card.name = std::filesystem::path(model_path).stem().string();
  card.kind = semantic::ModelKind::kTorch;
  card.model = model_path;
  card.mean = {127.5, 127.5, 127.5};
  card.scale = 1.0 / 127.5;
  card.rgb = true;
  CompleteTorchCard(&card);
  return card;
}

semantic::ModelCard LoadAnyModelCard(const std::string& path, const std::string& shared_root) {
  semantic::ModelCard card = semantic::LoadModelCard(path, shared_root);
  if (card.kind == semantic::ModelKind::kTorch) CompleteTorchCard(&card);
  return card;
}

TorchMaskProvider::TorchMaskProvider(const semantic::ModelCard& card,
                                     const semantic::RefineOptions& refine, int num_threads)
    : segmenter_(std::make_unique<TorchSegmenter>(RequireTorch(card).model, num_threads)),
      card_(Completed(card, segmenter_->config())),
      movable_(card_.MovableFlags()),
      refiner_(refine, movable_, card_.BackgroundIndex()) {
  segmenter_->set_input_size({card_.input_width, card_.input_height});
  if (card_.movable.empty()) {
    spdlog::warn("{}: no class is movable; every mask is empty", card_.path);
  }
}

TorchMaskProvider::~TorchMaskProvider() = default;

semantic::Prediction TorchMaskProvider::Predict(const semantic::MaskInput& input) {
  const auto start = Clock::now();
  if (input.image.empty()) ThrowInput("{}: no image to segment", card_.name);
  // TorchSegmenter takes grey or BGR; ToBgr drops an alpha channel and rejects other types.
  const cv::Mat image = input.image.type() == CV_8UC1 ? input.image : semantic::ToBgr(input.image);
  TorchSegmentation out = segmenter_->Run(image);
  const int num = static_cast<int>(card_.classes.size());
  if (out.probabilities.dims != 3 || out.probabilities.type() != CV_32F ||
      out.probabilities.size[0] != num || static_cast<int>(out.class_scores.size()) != num) {
    ThrowInFile(card_.model, fmt::format("the network's output is not {} planes of probabilities "
                                         "with {} class scores",
                                         num, num));
  }
  // The softmax is interpolated (bilinear weights are convex, so each pixel still sums to 1);
  // TorchSegmenter gives probabilities, not logits.
  cv::Mat probabilities = semantic::ResizePlanar(
      out.probabilities, semantic::WorkingSize(input.image.size(), refiner_.options().working_side),
      cv::INTER_LINEAR);
  semantic::Prediction prediction;
  prediction.probabilities = std::move(probabilities);
  prediction.image_scores = std::move(out.class_scores);
  prediction.network_ms = MsSince(start);
  return prediction;
}

semantic::MaskResult TorchMaskProvider::Refine(semantic::Prediction prediction,
                                               const semantic::MaskInput& input) {
  return semantic::RefinePrediction(refiner_, std::move(prediction), input);
}

std::string TorchMaskProvider::Describe() const {
  const semantic::RefineOptions& refine = refiner_.options();
  std::string text = fmt::format("torch {} {}x{} (movable: {}), crf {}, working side {} px",
                                 card_.name, segmenter_->input_size().width,
                                 segmenter_->input_size().height, fmt::join(card_.movable, ", "),
                                 semantic::ToString(refine.crf), refine.working_side);
  if (refine.suppress_below > 0.0f) text += fmt::format(", suppress < {}", refine.suppress_below);
  if (refine.movable_bias != 0.0f) text += fmt::format(", movable bias {}", refine.movable_bias);
  if (refine.dilate_px > 0) text += fmt::format(", dilated {} px", refine.dilate_px);
  return text;
}

std::unique_ptr<semantic::MaskProvider> MakeAnyMaskProvider(const semantic::ModelCard& card,
                                                            const semantic::RefineOptions& refine) {
  if (card.kind == semantic::ModelKind::kTorch) {
    return std::make_unique<TorchMaskProvider>(card, refine, card.threads);
  }
  return semantic::MakeMaskProvider(card, refine);
}

}  // namespace moslam::net
