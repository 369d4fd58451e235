// The networks of the weakly supervised pipeline (Sun, Tai, Gao, Liu, Yeung 2019, "Fully using
// classifiers for weakly supervised semantic segmentation with modified cues"; its segmentation
// stage follows SEC, Kolesnikov and Lampert, ECCV 2016): a multi-label classifier whose class
// activation maps (Zhou et al., CVPR 2016) give localization cues, and a segmentation network
// trained on those cues. Both share the MobileNetV2 backbone (mobilenet_v2.h).
//
// Class conventions:
//   classifier: `classes` are the image-level classes, in label-vector order (no background
//               entry unless the dataset names one as an ordinary class);
//   segmenter:  output channel l is class l of NetConfig::classes.
// `classes` of a segmenter are those of the classifiers whose cues trained it.
#pragma once

#include <string>
#include <vector>

#include <torch/torch.h>
#include <nlohmann/json_fwd.hpp>
#include <opencv2/core.hpp>

#include "moslam/net/mobilenet_v2.h"

namespace moslam::net {

enum class NetKind { kClassifier, kSegmenter };

// Smallest input side a network takes (pixels): below it the stride-16 features are a cell or two.
constexpr int kMinInputSide = 32;

// Everything needed to rebuild a network and feed it: saved inside every model file.
struct NetConfig {
  NetKind kind = NetKind::kClassifier;
  std::vector<std::string> classes;
  std::vector<std::string> movable;  // subset of classes
  // Name of the class that means "none of the others" (seeds where every class is weak; never
  // suppressed at test time); empty when every pixel belongs to a named class (CamVid).
  std::string background;
  BackboneOptions backbone;
  // Segmenter head: a light ASPP (Chen et al. 2017): parallel 3x3 convs with these dilations
  // plus a 1x1 branch and image pooling, `head_channels` each, then a 1x1 conv to the classes.
  int head_channels = 96;
  std::vector<int> head_dilations = {2, 4, 6};
  // Optional decoder (DeepLabV3+, Chen et al. 2018): the head's output, bilinearly upsampled to
  // the resolution of backbone block `decoder_block`, is concatenated with that block's features
  // (projected to 32 channels) and refined by a depthwise-separable 3x3 conv with
  // `decoder_channels` outputs before the class conv, so the logits come at that block's stride
  // (block 3: stride 4) and small objects keep their outline, which bilinear upsampling of
  // stride-16 logits cannot give (on the synthetic held-out frames, even perfect stride-16 logits
  // reach a person IoU of only 0.85). 0: no decoder, logits at the backbone's output stride.
  int decoder_block = 0;
  int decoder_channels = 64;
  // Input: images are resized to input_width x input_height (pixels) and given as RGB in
  // [-1, 1]; grey networks get the grey image in all three channels.
  int input_width = 320;
  int input_height = 240;
  bool grey = false;

  void Check() const;  // InputError naming the field
  int num_classes() const { return static_cast<int>(classes.size()); }
  int BackgroundIndex() const;  // -1 when `background` is empty
};
nlohmann::json ToJson(const NetConfig& config);
NetConfig NetConfigFromJson(const nlohmann::json& json);  // InputError on unknown/missing keys

struct ClassifierOutput {
  torch::Tensor logits;  // N x C, before the sigmoid
  torch::Tensor cams;    // N x C x h x w class activation maps (the 1x1-conv class map), at the
                         // backbone's output stride; logits = spatial mean of cams
};

// Backbone -> 1x1 conv to C class maps -> global average pooling (Zhou et al. 2016, with the
// class map computed before pooling so that it is the CAM itself).
class ClassifierNetImpl : public torch::nn::Module {
 public:
  explicit ClassifierNetImpl(const NetConfig& config);
  ClassifierOutput forward(torch::Tensor x);
  const NetConfig& config() const { return config_; }
  MobileNetV2& backbone() { return backbone_; }

 private:
  NetConfig config_;
  MobileNetV2 backbone_{nullptr};
  torch::nn::Conv2d class_map_{nullptr};
};
TORCH_MODULE(ClassifierNet);

struct SegmenterOutput {
  torch::Tensor logits;        // N x C x h x w per-pixel class scores at the backbone's stride
                               // (the decoder block's stride with a decoder)
  torch::Tensor class_logits;  // N x C image-level scores (an auxiliary classifier on the same
                               // backbone: what test-time suppression reads, at no extra cost)
};

class SegmenterNetImpl : public torch::nn::Module {
 public:
  explicit SegmenterNetImpl(const NetConfig& config);
  SegmenterOutput forward(torch::Tensor x);
  const NetConfig& config() const { return config_; }
  MobileNetV2& backbone() { return backbone_; }

 private:
  NetConfig config_;
  MobileNetV2 backbone_{nullptr};
  torch::nn::ModuleList aspp_{nullptr};
  torch::nn::Sequential image_pool_{nullptr};
  torch::nn::Sequential project_{nullptr};
  // Decoder (NetConfig::decoder_block): block features -> 32 channels (conv, ReLU); a depthwise
  // 3x3 and a pointwise conv on [upsampled head, low-level] (conv, ReLU, conv, ReLU).
  torch::nn::Sequential low_level_{nullptr};
  torch::nn::Sequential decoder_{nullptr};
  torch::nn::Conv2d classify_{nullptr};
  torch::nn::Conv2d aux_class_map_{nullptr};
};
TORCH_MODULE(SegmenterNet);

// Bilinear upsampling (align_corners false, as inference does) of N x C x h x w maps to
// N x C x height x width: the decoder's head, and the logits and CAMs of every training stage.
torch::Tensor UpsampleBilinear(const torch::Tensor& maps, int64_t height, int64_t width);

// Image (CV_8UC3 BGR or CV_8UC1 grey, any size) -> 1 x 3 x size.height x size.width float tensor
// (resized with INTER_AREA when shrinking, grey replicated, or colour converted to grey when
// `grey`); the second form at the config's input size and grey flag.
torch::Tensor ImageToTensor(const cv::Mat& image, cv::Size size, bool grey);
torch::Tensor ImageToTensor(const cv::Mat& image, const NetConfig& config);

}  // namespace moslam::net
