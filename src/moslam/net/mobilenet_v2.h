// MobileNetV2 (M. Sandler, A. Howard, M. Zhu, A. Zhmoginov, L.-C. Chen, "MobileNetV2: Inverted
// residuals and linear bottlenecks", CVPR 2018) as a libtorch C++ module: the backbone of the
// weakly supervised classifiers and segmentation networks (weak/, net/networks.h).
//
// Blocks follow torchvision's `mobilenet_v2().features` numbering: features.0 is the stem
// (3x3 conv, stride 2, 32 channels), features.1..17 the inverted residual blocks, features.18 the
// final 1x1 conv to 1280 channels. The backbone may stop early (`last_block`) and may replace the
// strides of later blocks by dilation (`output_stride`), as DeepLabV3 does (Chen et al. 2017).
//
// BatchNorm is folded: the shared ImageNet weights (../shared/models/mobilenet_v2_imagenet) were
// dequantized with BN weight 1, mean 0, variance 1 - eps, so BN(x) = x + bias. Each conv here has a
// bias instead of a BatchNorm, initialized from that BN bias; nothing has batch statistics, so
// training with small batches (or one image) behaves exactly like inference.
#pragma once

#include <string>

#include <torch/torch.h>

#include "moslam/net/fused_pointwise.h"

namespace moslam::net {

struct BackboneOptions {
  // Last torchvision block kept, 1..18. 13 ends with 96 channels at stride 16 (the cheapest
  // backbone that still has the stride-16 receptive field); 17: 320 channels; 18: 1280.
  int last_block = 13;
  // Requested output stride: 8, 16 or 32. Blocks that would reduce the resolution below it keep
  // stride 1 and dilate their 3x3 depthwise conv instead (and every later one), so the
  // pretrained weights still apply. Must not exceed the natural stride of `last_block`.
  int output_stride = 16;
  // Blocks 0..frozen_blocks-1 get requires_grad = false (their backward pass is skipped
  // entirely, which is most of the training cost at high resolution). 0 = train everything.
  int frozen_blocks = 0;

  // Throws InputError naming the field.
  void Check() const;
};

// Channels and natural stride (without dilation) after torchvision block `block` (0..18).
int BlockChannels(int block);
int BlockStride(int block);

class MobileNetV2Impl : public torch::nn::Module {
 public:
  explicit MobileNetV2Impl(const BackboneOptions& options = {});

  // x: N x 3 x H x W, RGB scaled to [-1, 1] (x / 127.5 - 1). Returns N x out_channels() x
  // ceil(H / stride) x ceil(W / stride).
  torch::Tensor forward(torch::Tensor x);
  // The same, also returning the output of block `tap` (0..last_block) in *tapped: the
  // low-level features of a decoder (DeepLabV3+, Chen et al. 2018).
  torch::Tensor forward(torch::Tensor x, int tap, torch::Tensor* tapped);

  const BackboneOptions& options() const { return options_; }
  int out_channels() const;
  int output_stride() const;  // the effective stride after dilation

  // Applies options().frozen_blocks (call again after loading weights).
  void ApplyFreezing();

 private:
  torch::Tensor Run(const torch::Tensor& x, int tap, torch::Tensor* tapped);  // tap -1: none

  BackboneOptions options_;
  torch::nn::Sequential blocks_{nullptr};  // one entry per torchvision block 0..last_block
};
TORCH_MODULE(MobileNetV2);

// Copies ImageNet weights from the shared TorchScript file (torchvision parameter names such as
// `features.3.conv.1.0.weight`), folding each BatchNorm into the preceding conv's bias. Throws
// InputError when the file is missing, unreadable or a tensor's shape disagrees.
// A 1x1 convolution (stride 1, one group, with bias) as one matrix product on the NHWC layout
// (no copy when x is channels-last), avoiding libtorch 1.13's single-threaded im2col path.
torch::Tensor Pointwise(const torch::Tensor& x, const torch::Tensor& weight,
                        const torch::Tensor& bias);
// activation(conv(x)). A 1x1 convolution (stride 1, one group, with bias) runs as one oneDNN
// matmul with the bias and activation fused where no gradient is wanted (FusedPointwise), and
// through Pointwise otherwise; any other convolution through libtorch.
torch::Tensor ApplyConv(torch::nn::Conv2dImpl& conv, const torch::Tensor& x,
                        Activation activation = Activation::kNone);

void LoadImageNetWeights(const std::string& torchscript_path, MobileNetV2& backbone);

// Stores every 4-D parameter of `module` (conv weights) in channels-last (NHWC) memory order.
// libtorch 1.13's oneDNN depthwise convolution is ~20x faster on NHWC than on NCHW tensors (NCHW
// pays a layout reorder per call), which makes it the dominant term of MobileNetV2 otherwise. The
// networks here call it on construction and feed NHWC input; results are the same up to rounding.
void UseChannelsLast(torch::nn::Module& module);

// ../shared/models/mobilenet_v2_imagenet/mobilenet_v2_imagenet.torchscript.pt under SharedRoot().
std::string DefaultImageNetWeightsPath();

}  // namespace moslam::net
