// Movable-object masks from an object detector (Darknet YOLO cfg + weights, or an ONNX detector
// that cv::dnn::DetectionModel understands): every kept box of a movable class becomes a filled
// rectangle. The coarse-box baseline the paper argues against (Sun et al. 2019, Sec. I): boxes
// also cover the static background around a person.
//
// Classes of the result: "static" (0) and then the card's movable classes in card order. Inside
// a box of movable class m, plane m gets the card's box_probability and "static" the rest; outside
// every box, "static" is 1; the planes are then normalized. This makes the box mask the argmax and
// lets the CRF (--crf c|d|cd) shrink boxes to the object's colour or depth edges.
#pragma once

#include <string>
#include <vector>

#include <opencv2/dnn.hpp>

#include "moslam/semantic/mask_provider.h"

namespace moslam::semantic {

class BoxDetector : public MaskProvider {
 public:
  // InputError naming the model or config file when OpenCV cannot load them.
  BoxDetector(const ModelCard& card, const RefineOptions& refine);
  Prediction Predict(const MaskInput& input) override;
  MaskResult Refine(Prediction prediction, const MaskInput& input) override;
  const std::vector<std::string>& class_names() const override { return names_; }
  const std::vector<bool>& movable() const override { return movable_; }
  std::string Describe() const override;

  // The probability planes described above for `detections` (image coordinates) at `working`
  // size, for an image of `image_size`. plane_of: card class index -> plane (0 = not movable).
  static cv::Mat BoxProbabilities(const std::vector<Detection>& detections,
                                  const std::vector<int>& plane_of, int num_planes,
                                  float box_probability, const cv::Size& image_size,
                                  const cv::Size& working);

 private:
  ModelCard card_;
  std::vector<std::string> names_;
  std::vector<bool> movable_;
  std::vector<int> plane_of_;
  MaskRefiner refiner_;
  cv::dnn::DetectionModel model_;
};

}  // namespace moslam::semantic
