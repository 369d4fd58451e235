#include "moslam/semantic/box_detector.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>

#include <fmt/ranges.h>

#include "moslam/semantic/dnn_provider_util.h"

namespace moslam::semantic {

using internal::Clock;
using internal::MsSince;
using internal::ReadNet;
using internal::RefineText;
using internal::RunNetwork;

namespace {

std::vector<int> PlaneOf(const ModelCard& card, std::vector<std::string>* names) {
  names->assign(1, "static");
  std::vector<int> plane_of(card.classes.size(), 0);
  for (size_t i = 0; i < card.classes.size(); ++i) {
    if (std::find(card.movable.begin(), card.movable.end(), card.classes[i]) ==
        card.movable.end()) {
      continue;
    }
    plane_of[i] = static_cast<int>(names->size());
    names->push_back(card.classes[i]);
  }
  return plane_of;
}

}  // namespace

namespace internal {

void CheckDarknetWeightsSize(const ModelCard& card, const cv::dnn::Net& net) {
  // Darknet's header: major, minor, revision (int32), then the images seen: a uint64 from
  // version 0.2 on, an int32 before (as OpenCV's reader and Darknet's load_weights read it).
  std::ifstream in(card.model, std::ios::binary);
  int32_t version[3] = {0, 0, 0};
  if (!in.read(reinterpret_cast<char*>(version), sizeof(version))) {
    ThrowInFile(card.model,
                fmt::format("too short for Darknet weights (no header; card {})", card.path));
  }
  const uintmax_t header = sizeof(version) + (version[0] * 10 + version[1] >= 2 ? 8 : 4);
  // What the layers that OpenCV's reader fills from the file hold (convolutions, their batch
  // normalizations, fully connected layers); other layers' blobs come from the .cfg (a Region
  // layer's anchors).
  uintmax_t expected = 0;
  for (const std::string& name : net.getLayerNames()) {
    const cv::Ptr<cv::dnn::Layer> layer = net.getLayer(name);
    if (layer->type != "Convolution" && layer->type != "BatchNorm" &&
        layer->type != "InnerProduct") {
      continue;
    }
    for (const cv::Mat& blob : layer->blobs) expected += blob.total() * blob.elemSize();
  }
  std::error_code error;
  const uintmax_t size = std::filesystem::file_size(card.model, error);
  if (error || size < header + expected) {
    ThrowInFile(
        card.model,
        fmt::format("holds {} bytes, but the network of {} (config {}) needs {} (a {}-byte "
                    "header and {} bytes of weights): the file is truncated or belongs to "
                    "another network",
                    error ? 0 : size, card.path, card.config, header + expected, header, expected));
  }
}

}  // namespace internal

BoxDetector::BoxDetector(const ModelCard& card, const RefineOptions& refine)
    : card_(card),
      plane_of_(PlaneOf(card, &names_)),
      refiner_(
          refine,
          [&] {
            std::vector<bool> flags(names_.size(), true);
            flags[0] = false;
            return flags;
          }(),
          0),
      model_(ReadNet(card)) {
  movable_.assign(names_.size(), true);
  movable_[0] = false;
  model_.setInputParams(card_.scale, cv::Size(card_.input_width, card_.input_height),
                        cv::Scalar(card_.mean[0], card_.mean[1], card_.mean[2]), card_.rgb, false);
}

cv::Mat BoxDetector::BoxProbabilities(const std::vector<Detection>& detections,
                                      const std::vector<int>& plane_of, int num_planes,
                                      float box_probability, const cv::Size& image_size,
                                      const cv::Size& working) {
  const int sizes[3] = {num_planes, working.height, working.width};
  cv::Mat planes(3, sizes, CV_32F, cv::Scalar(0));
  LabelPlane(planes, 0).setTo(1.0f);
  const double sx = static_cast<double>(working.width) / image_size.width;
  const double sy = static_cast<double>(working.height) / image_size.height;
  const cv::Rect bounds(0, 0, working.width, working.height);
  for (const Detection& d : detections) {
    const int plane = plane_of.at(d.class_id);
    if (plane == 0) continue;
    // Outward rounding: a box never shrinks below the pixels it touches.
    const int x0 = static_cast<int>(std::floor(d.box.x * sx));
    const int y0 = static_cast<int>(std::floor(d.box.y * sy));
    const int x1 = static_cast<int>(std::ceil((d.box.x + d.box.width) * sx));
    const int y1 = static_cast<int>(std::ceil((d.box.y + d.box.height) * sy));
    const cv::Rect box = cv::Rect(x0, y0, x1 - x0, y1 - y0) & bounds;
    if (box.empty()) continue;
    LabelPlane(planes, plane)(box).setTo(box_probability);
    LabelPlane(planes, 0)(box).setTo(1.0f - box_probability);
  }
  cv::Mat sum(working, CV_32F, cv::Scalar(0));
  for (int l = 0; l < num_planes; ++l) sum += LabelPlane(planes, l);
  for (int l = 0; l < num_planes; ++l) {
    cv::Mat plane = LabelPlane(planes, l);
    cv::divide(plane, sum, plane);
  }
  return planes;
}

Prediction BoxDetector::Predict(const MaskInput& input) {
  const auto start = Clock::now();
  const cv::Mat bgr = ToBgr(input.image);
  std::vector<int> ids;
  std::vector<float> confidences;
  std::vector<cv::Rect> boxes;
  RunNetwork(card_, [&] {
    model_.detect(bgr, ids, confidences, boxes, card_.confidence, card_.nms);
    return 0;
  });
  Prediction result;
  const cv::Rect bounds(0, 0, bgr.cols, bgr.rows);
  for (size_t i = 0; i < ids.size(); ++i) {
    if (ids[i] < 0 || ids[i] >= static_cast<int>(card_.classes.size())) {
      ThrowInFile(card_.path, fmt::format("the detector gave class {}, but the card lists {} "
                                          "classes",
                                          ids[i], card_.classes.size()));
    }
    const cv::Rect box = boxes[i] & bounds;
    if (!box.empty()) result.detections.push_back({ids[i], confidences[i], box});
  }
  result.probabilities = BoxProbabilities(
      result.detections, plane_of_, static_cast<int>(names_.size()), card_.box_probability,
      bgr.size(), WorkingSize(bgr.size(), refiner_.options().working_side));
  result.network_ms = MsSince(start);
  return result;
}

MaskResult BoxDetector::Refine(Prediction prediction, const MaskInput& input) {
  return RefinePrediction(refiner_, std::move(prediction), input);
}

std::string BoxDetector::Describe() const {
  return fmt::format("detector {} {}x{} (movable: {}; confidence {}, nms {}){}", card_.name,
                     card_.input_width, card_.input_height, fmt::join(card_.movable, ", "),
                     card_.confidence, card_.nms, RefineText(refiner_.options()));
}

}  // namespace moslam::semantic
