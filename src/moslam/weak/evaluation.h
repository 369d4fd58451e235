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

// Accumulates over a set of images. Pixels whose label is in ignore_labels are not counted at all.
// A counted pixel whose label maps to -1 (or, with the identity mapping, is not below the number
// of classes) is a false positive of the class predicted there and no class's truth; it is kept in
// unmatched() beside the confusion matrix. Movable truth: movable_labels, or, when that is empty,
// the movable flag of the label's class; movable prediction: movable_classes (none when empty).
class SegEvaluator {
 public:
  // InputError for 0 or more than 255 classes, a mapping to no class, movable_classes of another
  // length than the classes, or label ids beyond 8 bits.
  SegEvaluator(std::vector<std::string> class_names, SegEvalOptions options);

  // prediction: H x W CV_8U class indices; labels: H x W CV_8U ground-truth ids (same size).
  // Returns the binary movable IoU of this image (1 when neither has movable pixels).
  // InputError for other types or sizes, or a predicted index >= the number of classes.
  double Add(const cv::Mat& prediction, const cv::Mat& labels);

  std::vector<double> ClassIoU() const;  // NaN for classes absent from both
  double MeanIoU() const;                // over classes that are not NaN
  double MovableIoU() const;             // binary, over all images
  double MovablePrecision() const;
  double MovableRecall() const;
  // Share of counted pixels whose class was predicted (unmatched pixels count as wrong).
  double PixelAccuracy() const;
  const cv::Mat& confusion() const { return confusion_; }  // CV_64F rows: truth, cols: predicted
  // 1 x C CV_64F: pixels predicted as each class whose label has no class.
  const cv::Mat& unmatched() const { return unmatched_; }
  const std::vector<std::string>& class_names() const { return class_names_; }
  int num_classes() const { return static_cast<int>(class_names_.size()); }
  int images() const { return images_; }
  // Per-class IoU, mean IoU, pixel accuracy, the movable scores and the confusion matrix; NaN
  // values are written as null.
  nlohmann::json ToJson() const;

 private:
  bool IsMovableClass(int c) const;

  std::vector<std::string> class_names_;
  SegEvalOptions options_;
  std::vector<int> class_of_label_;  // per label id 0..255: class, -1 none, -2 ignored
  std::vector<bool> truth_movable_;  // per label id 0..255
  cv::Mat confusion_;
  cv::Mat unmatched_;
  double movable_tp_ = 0, movable_fp_ = 0, movable_fn_ = 0;
  double ignored_pixels_ = 0;
  int images_ = 0;
};

// CamVid's 11 class names in label-id order (SegNet's split; id 11 is "unlabelled").
const std::vector<std::string>& CamVidLabelNames();

// SegEvalOptions::label_to_class by name: label id i (named label_names[i]) maps to the class of
// the same name, compared case-insensitively; a label whose name is not a class maps to
// `background` (-1: no counterpart). Empty (the identity mapping) when no name matches at all.
std::vector<int> LabelToClassByName(const std::vector<std::string>& label_names,
                                    const std::vector<std::string>& classes, int background);

// The confusion matrix as an image (rows normalized, class names on both axes).
cv::Mat RenderConfusion(const cv::Mat& confusion, const std::vector<std::string>& class_names);

}  // namespace moslam::weak
