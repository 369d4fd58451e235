#include "moslam/api/segmenter.h"

#include "moslam/semantic/mask_provider.h"
#include "moslam/semantic/model_card.h"

namespace moslam::api {

struct Segmenter::Impl {
  std::unique_ptr<semantic::MaskProvider> provider;
};

Segmenter::Segmenter(const std::string& model_card) : impl_(std::make_unique<Impl>()) {
  const semantic::ModelCard card = semantic::LoadModelCard(model_card);
  impl_->provider = semantic::MakeMaskProvider(card, card.refine);
}

Segmenter::~Segmenter() = default;

Segmentation Segmenter::Segment(const cv::Mat& image, const cv::Mat& depth) {
  semantic::MaskInput input;
  input.image = image;
  input.depth = depth;
  semantic::MaskResult result = impl_->provider->Segment(input);
  return {result.probabilities, result.mask};
}

const std::vector<std::string>& Segmenter::classes() const {
  return impl_->provider->class_names();
}
const std::vector<bool>& Segmenter::movable() const { return impl_->provider->movable(); }
std::string Segmenter::Describe() const { return impl_->provider->Describe(); }

}  // namespace moslam::api
