// Evaluation of a segmentation against pixel labels (the only place pixel labels are read in the
// weak pipeline): a confusion matrix, per-class IoU and the binary movable-vs-static IoU.
#pragma once

#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace moslam::weak {

struct SegEvalOptions {
  // Label ids that are not counted (CamVid: 11, unlabelled).
  std::vector<int> ignore_labels = {11};
  // Mapping from ground-truth label id to predicted class index (-1: no counterpart, counted as
  // a miss of every class); the identity when empty.
  std::vector<int> label_to_class;
  std::vector<bool> movable_labels;   // per ground-truth label id: is it movable
  std::vector<bool> movable_classes;  // per predicted class: is it movable
};

// Accumulates over a set of images.
class SegEvaluator {
 public:
  SegEvaluator(std::vector<std::string> class_names, SegEvalOptions options);

  // prediction: H x W CV_8U class indices; labels: H x W CV_8U ground-truth ids (same size).
  // Returns the binary movable IoU of this image (1 when neither has movable pixels).
  double Add(const cv::Mat& prediction, const cv::Mat& labels);

  std::vector<double> ClassIoU() const;  // NaN for classes absent from both
  double MeanIoU() const;                // over classes that are not NaN
  double MovableIoU() const;             // binary, over all images
  double MovablePrecision() const;
  double MovableRecall() const;
  const cv::Mat& confusion() const { return confusion_; }  // CV_64F rows: truth, cols: predicted
  nlohmann::json ToJson() const;

 private:
  std::vector<std::string> class_names_;
  SegEvalOptions options_;
  cv::Mat confusion_;
  double movable_tp_ = 0, movable_fp_ = 0, movable_fn_ = 0;
};

// The confusion matrix as an image (rows normalized, class names on both axes).
cv::Mat RenderConfusion(const cv::Mat& confusion, const std::vector<std::string>& class_names);

}  // namespace moslam::weak
