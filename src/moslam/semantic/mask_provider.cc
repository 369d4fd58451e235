#include "moslam/semantic/mask_provider.h"

#include <chrono>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <opencv2/imgproc.hpp>

#include "moslam/semantic/box_detector.h"
#include "moslam/semantic/onnx_segmenter.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

using Clock = std::chrono::steady_clock;

double MsSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

cv::dnn::Net ReadNet(const ModelCard& card) {
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

std::string RefineText(const RefineOptions& refine) {
  std::string text =
      fmt::format(", crf {}, working side {} px", ToString(refine.crf), refine.working_side);
  if (refine.suppress_below > 0.0f) text += fmt::format(", suppress < {}", refine.suppress_below);
  if (refine.dilate_px > 0) text += fmt::format(", dilated {} px", refine.dilate_px);
  return text;
}

void CopyRefined(RefineResult&& refined, MaskResult* result) {
  result->mask = std::move(refined.mask);
  result->probabilities = std::move(refined.probabilities);
  result->labels = std::move(refined.labels);
  result->image_scores = std::move(refined.image_scores);
  result->suppressed = std::move(refined.suppressed);
  result->crf_ms = refined.crf_ms;
}

}  // namespace

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
  if (card.kind == ModelKind::kDetector) return std::make_unique<BoxDetector>(card, refine);
  return std::make_unique<OnnxSegmenter>(card, refine);
}

OnnxSegmenter::OnnxSegmenter(const ModelCard& card, const RefineOptions& refine)
    : card_(card),
      movable_(card.MovableFlags()),
      refiner_(refine, movable_, card.BackgroundIndex()),
      net_(ReadNet(card)) {}

MaskResult OnnxSegmenter::Segment(const MaskInput& input) {
  const auto start = Clock::now();
  const cv::Mat bgr = ToBgr(input.image);
  const cv::Mat blob = cv::dnn::blobFromImage(
      bgr, card_.scale, cv::Size(card_.input_width, card_.input_height),
      cv::Scalar(card_.mean[0], card_.mean[1], card_.mean[2]), card_.rgb, false, CV_32F);
  net_.setInput(blob);
  cv::Mat out = net_.forward();
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
  MaskResult result;
  result.network_ms = MsSince(start);
  CopyRefined(refiner_.Refine(std::move(probabilities), input.image, input.depth), &result);
  result.total_ms = MsSince(start);
  return result;
}

std::string OnnxSegmenter::Describe() const {
  return fmt::format("onnx {} {}x{} (movable: {}){}", card_.name, card_.input_width,
                     card_.input_height, fmt::join(card_.movable, ", "),
                     RefineText(refiner_.options()));
}

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

MaskResult BoxDetector::Segment(const MaskInput& input) {
  const auto start = Clock::now();
  const cv::Mat bgr = ToBgr(input.image);
  std::vector<int> ids;
  std::vector<float> confidences;
  std::vector<cv::Rect> boxes;
  model_.detect(bgr, ids, confidences, boxes, card_.confidence, card_.nms);
  MaskResult result;
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
  cv::Mat probabilities = BoxProbabilities(
      result.detections, plane_of_, static_cast<int>(names_.size()), card_.box_probability,
      bgr.size(), WorkingSize(bgr.size(), refiner_.options().working_side));
  result.network_ms = MsSince(start);
  CopyRefined(refiner_.Refine(std::move(probabilities), input.image, input.depth), &result);
  result.total_ms = MsSince(start);
  return result;
}

std::string BoxDetector::Describe() const {
  return fmt::format("detector {} {}x{} (movable: {}; confidence {}, nms {}){}", card_.name,
                     card_.input_width, card_.input_height, fmt::join(card_.movable, ", "),
                     card_.confidence, card_.nms, RefineText(refiner_.options()));
}

}  // namespace moslam::semantic
