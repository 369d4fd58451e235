// Semantic segmentation with any ONNX model OpenCV dnn can load (model_card.h says how): the
// image is resized to the network's input, the output logits {1, L, H, W} are resized to the
// working size and turned into probabilities (softmax over the classes), then refined into the
// movable mask (mask_refine.h). Checked with DeepLabV3-MobileNetV2 trained on PASCAL VOC, the
// fully supervised baseline of the paper's comparison.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/dnn.hpp>

#include "moslam/semantic/mask_provider.h"

namespace moslam::semantic {

class OnnxSegmenter : public MaskProvider {
 public:
  // InputError naming the model file when OpenCV cannot load it.
  OnnxSegmenter(const ModelCard& card, const RefineOptions& refine);
  Prediction Predict(const MaskInput& input) override;
  MaskResult Refine(Prediction prediction, const MaskInput& input) override;
  const std::vector<std::string>& class_names() const override { return card_.classes; }
  const std::vector<bool>& movable() const override { return movable_; }
  std::string Describe() const override;

 private:
  ModelCard card_;
  std::vector<bool> movable_;
  MaskRefiner refiner_;
  cv::dnn::Net net_;
};

}  // namespace moslam::semantic
