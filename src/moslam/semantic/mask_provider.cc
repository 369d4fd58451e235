#include "moslam/semantic/mask_provider.h"

#include <chrono>

#include <opencv2/imgproc.hpp>

#include "moslam/semantic/box_detector.h"
#include "moslam/semantic/onnx_segmenter.h"
#include "moslam/util/error.h"

namespace moslam::semantic {

MaskResult MaskProvider::Segment(const MaskInput& input) {
  const auto start = std::chrono::steady_clock::now();
  MaskResult result = Refine(Predict(input), input);
  result.total_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

MaskResult RefinePrediction(MaskRefiner& refiner, Prediction&& prediction, const MaskInput& input) {
  RefineResult refined = refiner.Refine(std::move(prediction.probabilities), input.image,
                                        input.depth, prediction.image_scores);
  MaskResult result;
  result.mask = std::move(refined.mask);
  result.probabilities = std::move(refined.probabilities);
  result.labels = std::move(refined.labels);
  result.image_scores = std::move(refined.image_scores);
  result.suppressed = std::move(refined.suppressed);
  result.detections = std::move(prediction.detections);
  result.network_ms = prediction.network_ms;
  result.crf_ms = refined.crf_ms;
  return result;
}

cv::Mat ToBgr(const cv::Mat& image) {
  cv::Mat bgr;
  if (image.type() == CV_8UC3) {
    bgr = image;
  } else if (image.type() == CV_8UC1) {
    cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
  } else if (image.type() == CV_8UC4) {
    cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
  } else {
    ThrowInput("mask provider: the image must be 8-bit grey, BGR or BGRA");
  }
  return bgr;
}

std::unique_ptr<MaskProvider> MakeMaskProvider(const ModelCard& card, const RefineOptions& refine) {
  if (card.kind == ModelKind::kTorch) {
    // libtorch lives in net/, which depends on this module: net::MakeAnyMaskProvider builds these.
    ThrowInFile(card.path, "type: torch cards are run by net::MakeAnyMaskProvider (libtorch)");
  }
  if (card.kind == ModelKind::kDetector) return std::make_unique<BoxDetector>(card, refine);
  return std::make_unique<OnnxSegmenter>(card, refine);
}

}  // namespace moslam::semantic
