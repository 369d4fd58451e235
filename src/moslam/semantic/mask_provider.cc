#include "moslam/semantic/mask_provider.h"

#include <opencv2/imgproc.hpp>

#include "moslam/semantic/box_detector.h"
#include "moslam/semantic/onnx_segmenter.h"
#include "moslam/util/error.h"

namespace moslam::semantic {

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
