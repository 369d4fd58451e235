// Shared by the OpenCV dnn providers (onnx_segmenter.cc, box_detector.cc); not a public header.
#pragma once

#include <chrono>
#include <string>

#include <fmt/format.h>
#include <opencv2/dnn.hpp>

#include "moslam/semantic/mask_provider.h"
#include "moslam/util/error.h"

namespace moslam::semantic::internal {

using Clock = std::chrono::steady_clock;

inline double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

inline cv::dnn::Net ReadNet(const ModelCard& card) {
  try {
    cv::dnn::Net net = card.config.empty() ? cv::dnn::readNet(card.model)
                                           : cv::dnn::readNetFromDarknet(card.config, card.model);
    net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    return net;
  } catch (const cv::Exception& e) {
    ThrowInFile(card.model,
                fmt::format("OpenCV dnn cannot load the model of {}: {}", card.path, e.what()));
  }
}

inline std::string RefineText(const RefineOptions& refine) {
  std::string text =
      fmt::format(", crf {}, working side {} px", ToString(refine.crf), refine.working_side);
  if (refine.suppress_below > 0.0f) text += fmt::format(", suppress < {}", refine.suppress_below);
  if (refine.movable_bias != 0.0f) text += fmt::format(", movable bias {}", refine.movable_bias);
  if (refine.dilate_px > 0) text += fmt::format(", dilated {} px", refine.dilate_px);
  return text;
}

}  // namespace moslam::semantic::internal
