// Shared by the OpenCV dnn providers (onnx_segmenter.cc, box_detector.cc); not a public header.
#pragma once

#include <chrono>
#include <string>

#include <fmt/format.h>
#include <opencv2/dnn.hpp>

#include "moslam/semantic/mask_provider.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::semantic::internal {

using Clock = std::chrono::steady_clock;

inline double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Throws InputError naming the weights and the card when a Darknet .weights file holds fewer
// bytes than the network it was loaded into: OpenCV's reader fills what a short file lacks with
// whatever the buffers held and says nothing, so a truncated file would run.
void CheckDarknetWeightsSize(const ModelCard& card, const cv::dnn::Net& net);

inline cv::dnn::Net ReadNet(const ModelCard& card) {
  cv::dnn::Net net;
  try {
    net = card.config.empty() ? cv::dnn::readNet(card.model)
                              : cv::dnn::readNetFromDarknet(card.config, card.model);
    net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
  } catch (const cv::Exception& e) {
    ThrowInFile(card.model, fmt::format("OpenCV dnn cannot load the model of {}: {}", card.path,
                                        Excerpt(e.what(), 400)));
  }
  if (!card.config.empty()) CheckDarknetWeightsSize(card, net);
  return net;
}

// Runs `forward` (the network on one image); an OpenCV error inside it, the network refusing the
// card's input size or normalization, becomes an InputError naming the card and its input size.
template <typename Forward>
auto RunNetwork(const ModelCard& card, Forward forward) -> decltype(forward()) {
  try {
    return forward();
  } catch (const cv::Exception& e) {
    ThrowInFile(card.path, fmt::format("the network ({}) cannot run at input_width x input_height "
                                       "= {}x{}: {}",
                                       card.model, card.input_width, card.input_height,
                                       Excerpt(e.what(), 400)));
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
