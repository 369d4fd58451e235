#include "moslam/net/torch_segmenter.h"

#include <utility>

#include <ATen/Parallel.h>

#include "moslam/net/model_file.h"
#include "moslam/util/error.h"

namespace moslam::net {

TorchSegmenter::TorchSegmenter(const std::string& model_path, int num_threads)
    : TorchSegmenter(LoadSegmenter(model_path)) {
  if (num_threads < 1) ThrowInput("TorchSegmenter: num_threads must be >= 1 (is {})", num_threads);
  // One intra-op pool per process: this also sets the threads of any other libtorch user.
  at::set_num_threads(num_threads);
}

TorchSegmenter::TorchSegmenter(SegmenterNet net)
    : net_(std::move(net)), input_size_(net_->config().input_width, net_->config().input_height) {
  net_->eval();
}

const NetConfig& TorchSegmenter::config() const { return net_->config(); }

void TorchSegmenter::set_input_size(cv::Size size) {
  if (size.width < kMinInputSide || size.height < kMinInputSide) {
    ThrowInput("TorchSegmenter: input size must be at least {0}x{0} pixels (is {1}x{2})",
               kMinInputSide, size.width, size.height);
  }
  input_size_ = size;
}

TorchSegmentation TorchSegmenter::Run(const cv::Mat& image) {
  // Inference mode skips autograd bookkeeping entirely (cheaper than NoGradGuard).
  c10::InferenceMode inference;
  const torch::Tensor input = ImageToTensor(image, input_size_, net_->config().grey);
  const SegmenterOutput out = net_->forward(input);
  const torch::Tensor probabilities = torch::softmax(out.logits[0], 0).contiguous();
  const torch::Tensor scores = torch::sigmoid(out.class_logits[0]).contiguous();

  TorchSegmentation result;
  const int sizes[3] = {static_cast<int>(probabilities.size(0)),
                        static_cast<int>(probabilities.size(1)),
                        static_cast<int>(probabilities.size(2))};
  // Wraps the tensor's memory, then copies it so that the Mat owns its data.
  result.probabilities =
      cv::Mat(3, sizes, CV_32F, const_cast<float*>(probabilities.data_ptr<float>())).clone();
  const float* s = scores.data_ptr<float>();
  result.class_scores.assign(s, s + scores.numel());
  return result;
}

}  // namespace moslam::net
