#include "moslam/runner/model_mask_source.h"

#include <filesystem>

#include <fmt/format.h>

#include "moslam/net/torch_mask_provider.h"
#include "moslam/semantic/model_card.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::runner {
namespace {

class ProviderMaskSource : public MaskSource {
 public:
  explicit ProviderMaskSource(std::unique_ptr<semantic::MaskProvider> provider)
      : provider_(std::move(provider)) {
    MOSLAM_CHECK(provider_ != nullptr);
  }
  FrameMask MaskFor(const io::FrameEntry& frame, const cv::Size&) const override {
    ThrowInput("frame {}: a network mask source needs the frame's image (Predict, not MaskFor)",
               frame.index);
  }
  bool Pipelined() const override { return true; }
  FrameMask Predict(const io::FrameEntry&, const cv::Mat& image, const cv::Mat& depth) override {
    FrameMask mask;
    mask.pending = std::make_shared<semantic::Prediction>(provider_->Predict({image, depth}));
    mask.network_ms = mask.pending->network_ms;
    return mask;
  }
  void Refine(FrameMask* mask, const cv::Mat& image, const cv::Mat& depth) override {
    MOSLAM_CHECK(mask->pending != nullptr) << "Refine() without Predict()";
    semantic::Prediction prediction = std::move(*mask->pending);
    mask->pending.reset();
    *mask = ToFrameMask(provider_->Refine(std::move(prediction), {image, depth}));
  }
  std::string Describe() const override { return provider_->Describe(); }

 private:
  static FrameMask ToFrameMask(semantic::MaskResult result) {
    FrameMask mask;
    mask.fraction = static_cast<double>(cv::countNonZero(result.mask)) /
                    static_cast<double>(result.mask.total());
    mask.mask = std::move(result.mask);
    mask.network_ms = result.network_ms;
    mask.crf_ms = result.crf_ms;
    return mask;
  }

  std::unique_ptr<semantic::MaskProvider> provider_;
};

semantic::ModelKind WantedKind(MaskSourceKind kind) {
  switch (kind) {
    case MaskSourceKind::kDetector:
      return semantic::ModelKind::kDetector;
    case MaskSourceKind::kModel:
      return semantic::ModelKind::kTorch;
    default:
      return semantic::ModelKind::kSegmentation;
  }
}

}  // namespace

std::unique_ptr<MaskSource> MakeProviderMaskSource(
    std::unique_ptr<semantic::MaskProvider> provider) {
  return std::make_unique<ProviderMaskSource>(std::move(provider));
}

std::unique_ptr<MaskSource> MakeModelMaskSource(const MaskOptions& options) {
  std::string card_path = options.model_card;
  if (card_path.empty() && options.kind == MaskSourceKind::kModel) {
    std::error_code ec;
    if (!std::filesystem::exists(kDefaultTorchCard, ec)) {
      ThrowInput(
          "--mask-source model: give the torch model card (--model-card), {} does not "
          "exist here",
          kDefaultTorchCard);
    }
    card_path = kDefaultTorchCard;
  }
  semantic::ModelCard card = semantic::LoadModelCard(card_path);
  const semantic::ModelKind wanted = WantedKind(options.kind);
  if (card.kind != wanted) {
    ThrowInFile(
        card.path,
        fmt::format(
            "type: is {}, but --mask-source {} needs a {} card{}", semantic::ToString(card.kind),
            ToString(options.kind), semantic::ToString(wanted),
            card.kind == semantic::ModelKind::kTorch ? " (torch cards: --mask-source model)" : ""));
  }
  // A torch card is completed from its model file first, so that --movable can name its classes.
  if (card.kind == semantic::ModelKind::kTorch) net::CompleteTorchCard(&card);
  if (!options.movable.empty()) semantic::SetMovable(options.movable, &card);
  semantic::RefineOptions refine = card.refine;
  if (options.crf) refine.crf = *options.crf;
  if (options.dilate_px > 0) refine.dilate_px = options.dilate_px;
  if (options.network_threads > 0) card.threads = options.network_threads;
  return MakeProviderMaskSource(net::MakeAnyMaskProvider(card, refine));
}

}  // namespace moslam::runner
