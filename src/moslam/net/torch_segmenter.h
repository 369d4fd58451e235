// Inference of a trained segmentation network (networks.h) for masks at run time: image in,
// per-class probabilities and image-level class scores out. The libtorch back end of
// semantic::MaskProvider (torch_mask_provider.h).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/net/networks.h"

namespace moslam::net {

struct TorchSegmentation {
  cv::Mat probabilities;            // {C, h, w} CV_32F softmax at the network's output stride
  std::vector<float> class_scores;  // per class: sigmoid of the auxiliary image-level logits
};

class TorchSegmenter {
 public:
  // Loads a segmenter model file; `num_threads` for at::set_num_threads (intra-op threads of
  // this process: libtorch has one pool). InputError when the file is not a segmenter.
  explicit TorchSegmenter(const std::string& model_path, int num_threads = 2);
  TorchSegmenter(SegmenterNet net);  // an in-memory network (tests, evaluation after training)

  // image: CV_8UC3 BGR or CV_8UC1 grey, any size (resized to the network's input).
  TorchSegmentation Run(const cv::Mat& image);
  const NetConfig& config() const;

  // The size images are resized to before the network (pixels; the model's input_width x
  // input_height unless set). The network is fully convolutional, so it runs at any size of at
  // least kMinInputSide (32) a side; a larger input resolves smaller objects at a cost that grows
  // with the area.
  cv::Size input_size() const { return input_size_; }
  void set_input_size(cv::Size size);  // InputError below 32 x 32

 private:
  SegmenterNet net_;
  cv::Size input_size_;
};

}  // namespace moslam::net
