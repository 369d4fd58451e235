#include "moslam/semantic/onnx_segmenter.h"

#include <fmt/ranges.h>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/dnn_provider_util.h"

namespace moslam::semantic {

using internal::Clock;
using internal::MsSince;
using internal::ReadNet;
using internal::RefineText;
using internal::RunNetwork;

OnnxSegmenter::OnnxSegmenter(const ModelCard& card, const RefineOptions& refine)
    : card_(card),
      movable_(card.MovableFlags()),
      refiner_(refine, movable_, card.BackgroundIndex()),
      net_(ReadNet(card)) {}

Prediction OnnxSegmenter::Predict(const MaskInput& input) {
  const auto start = Clock::now();
  const cv::Mat bgr = ToBgr(input.image);
  const cv::Mat blob = cv::dnn::blobFromImage(
      bgr, card_.scale, cv::Size(card_.input_width, card_.input_height),
      cv::Scalar(card_.mean[0], card_.mean[1], card_.mean[2]), card_.rgb, false, CV_32F);
  cv::Mat out = RunNetwork(card_, [&] {
    net_.setInput(blob);
    return net_.forward();
  });
  const int num = static_cast<int>(card_.classes.size());
  if (out.dims != 4 || out.size[0] != 1 || out.size[1] != num || out.type() != CV_32F) {
    ThrowInFile(card_.path, fmt::format("the model's output is not 1 x {} x H x W float logits "
                                        "({} dims, {} channels): does the card list its classes?",
                                        num, out.dims, out.dims > 1 ? out.size[1] : 0));
  }
  const cv::Mat logits(3, &out.size[1], CV_32F, out.ptr<float>());
  // Logits, not probabilities, are interpolated: resizing then softmax is the usual order
  // (DeepLab upsamples its logits) and costs the exponentials at the smaller size only.
  cv::Mat probabilities = ResizePlanar(
      logits, WorkingSize(input.image.size(), refiner_.options().working_side), cv::INTER_LINEAR);
  SoftmaxPlanar(&probabilities);
  Prediction prediction;
  prediction.probabilities = std::move(probabilities);
  prediction.network_ms = MsSince(start);
  return prediction;
}

MaskResult OnnxSegmenter::Refine(Prediction prediction, const MaskInput& input) {
  return RefinePrediction(refiner_, std::move(prediction), input);
}

std::string OnnxSegmenter::Describe() const {
  return fmt::format("onnx {} {}x{} (movable: {}){}", card_.name, card_.input_width,
                     card_.input_height, fmt::join(card_.movable, ", "),
                     RefineText(refiner_.options()));
}

}  // namespace moslam::semantic
