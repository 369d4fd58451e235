// Movable-object masks from a model card (configs/models/*.yaml: an ONNX segmentation network or
// detector run through OpenCV dnn, with the card's refinement), for programs that want the masks
// themselves (api::Slam computes them itself when given the card). Torch cards need libtorch
// (moslam::net), which the installed library leaves out: they are an InputError here.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace moslam::api {

struct Segmentation {
  cv::Mat probabilities;  // {classes, h, w} CV_32F at the network's working size
  cv::Mat mask;           // CV_8UC1 of the image's size: 255 = movable, 0 = static
};

class Segmenter {
 public:
  // InputError naming the card, the key or the model file.
  explicit Segmenter(const std::string& model_card);
  ~Segmenter();
  Segmenter(const Segmenter&) = delete;
  Segmenter& operator=(const Segmenter&) = delete;

  // image: CV_8UC3 BGR, CV_8UC4 BGRA or CV_8UC1; depth (for a card whose CRF uses it): CV_32FC1
  // metres of the image's size. InputError for other types.
  Segmentation Segment(const cv::Mat& image, const cv::Mat& depth = cv::Mat());
  const std::vector<std::string>& classes() const;
  const std::vector<bool>& movable() const;  // per class
  std::string Describe() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace moslam::api
