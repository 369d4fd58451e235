#include "moslam/net/networks.h"

#include <algorithm>
#include <set>

#include <nlohmann/json.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/util/error.h"

namespace moslam::net {
namespace {

const char* KindName(NetKind kind) {
  return kind == NetKind::kClassifier ? "classifier" : "segmenter";
}

NetKind KindFromName(const std::string& name) {
  if (name == "classifier") return NetKind::kClassifier;
  if (name == "segmenter") return NetKind::kSegmenter;
  ThrowInput("net config: kind must be 'classifier' or 'segmenter' (is '{}')", name);
}

bool Contains(const std::vector<std::string>& names, const std::string& name) {
  return std::find(names.begin(), names.end(), name) != names.end();
}

// Every key of `json` must be in `keys` or `optional` and every one of `keys` must be present.
void CheckKeys(const nlohmann::json& json, const std::set<std::string>& keys,
               const std::string& where, const std::set<std::string>& optional = {}) {
  if (!json.is_object()) ThrowInput("net config: {} must be a JSON object", where);
  for (const auto& item : json.items()) {
    if (keys.count(item.key()) == 0 && optional.count(item.key()) == 0)
      ThrowInput("net config: unknown key '{}' in {}", item.key(), where);
  }
  for (const std::string& key : keys) {
    if (!json.contains(key)) ThrowInput("net config: missing key '{}' in {}", key, where);
  }
}

template <typename T>
T Get(const nlohmann::json& json, const std::string& key) {
  try {
    return json.at(key).get<T>();
  } catch (const nlohmann::json::exception& e) {
    ThrowInput("net config: bad value of '{}': {}", key, e.what());
  }
}

torch::nn::Conv2d Conv(int in, int out, int kernel, int dilation = 1) {
  return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, kernel)
                               .padding(kernel == 3 ? dilation : 0)
                               .dilation(dilation)
                               .bias(true));
}

// New layers followed by a ReLU: He et al. 2015; class maps: small normal weights so that the
// initial scores are near zero and no class starts out dominant. Biases zero.
void InitReluConv(torch::nn::Conv2d& conv) {
  torch::NoGradGuard no_grad;
  torch::nn::init::kaiming_normal_(conv->weight, 0.0, torch::kFanIn, torch::kReLU);
  conv->bias.zero_();
}

void InitClassConv(torch::nn::Conv2d& conv) {
  torch::NoGradGuard no_grad;
  torch::nn::init::normal_(conv->weight, 0.0, 0.01);
  conv->bias.zero_();
}

torch::nn::Conv2dImpl& ConvAt(torch::nn::SequentialImpl& sequential, size_t i) {
  return *sequential.ptr(i)->as<torch::nn::Conv2dImpl>();
}

}  // namespace

void NetConfig::Check() const {
  if (classes.empty()) ThrowInput("net config: classes must not be empty");
  const std::set<std::string> unique(classes.begin(), classes.end());
  if (unique.size() != classes.size()) ThrowInput("net config: classes contain a duplicate name");
  for (const std::string& name : movable) {
    if (!Contains(classes, name)) ThrowInput("net config: movable class '{}' is not a class", name);
  }
  if (!background.empty() && !Contains(classes, background)) {
    ThrowInput("net config: background '{}' is not a class", background);
  }
  backbone.Check();
  if (head_channels < 1)
    ThrowInput("net config: head_channels must be >= 1 (is {})", head_channels);
  for (int d : head_dilations) {
    if (d < 1) ThrowInput("net config: head_dilations must be >= 1 (has {})", d);
  }
  if (decoder_block != 0) {
    if (decoder_block < 1 || decoder_block >= backbone.last_block ||
        BlockStride(decoder_block) >=
            std::min(backbone.output_stride, BlockStride(backbone.last_block))) {
      ThrowInput(
          "net config: decoder_block must be 0 (none) or a backbone block before last_block {} "
          "with a finer stride than the backbone's output (is {})",
          backbone.last_block, decoder_block);
    }
    if (decoder_channels < 1)
      ThrowInput("net config: decoder_channels must be >= 1 (is {})", decoder_channels);
  }
  if (input_width < kMinInputSide || input_height < kMinInputSide) {
    ThrowInput("net config: input_width and input_height must be >= {} pixels (are {} x {})",
               kMinInputSide, input_width, input_height);
  }
}

int NetConfig::BackgroundIndex() const {
  if (background.empty()) return -1;
  const auto it = std::find(classes.begin(), classes.end(), background);
  return it == classes.end() ? -1 : static_cast<int>(it - classes.begin());
}

nlohmann::json ToJson(const NetConfig& config) {
  nlohmann::json json;
  json["kind"] = KindName(config.kind);
  json["classes"] = config.classes;
  json["movable"] = config.movable;
  json["background"] = config.background;
  json["backbone"] = {{"last_block", config.backbone.last_block},
                      {"output_stride", config.backbone.output_stride},
                      {"frozen_blocks", config.backbone.frozen_blocks}};
  json["head_channels"] = config.head_channels;
  json["head_dilations"] = config.head_dilations;
  // Written only when present, so that files of decoder-less networks stay as they were.
  if (config.decoder_block != 0) {
    json["decoder"] = {{"block", config.decoder_block}, {"channels", config.decoder_channels}};
  }
  json["input_width"] = config.input_width;
  json["input_height"] = config.input_height;
  json["grey"] = config.grey;
  return json;
}

NetConfig NetConfigFromJson(const nlohmann::json& json) {
  CheckKeys(json,
            {"kind", "classes", "movable", "background", "backbone", "head_channels",
             "head_dilations", "input_width", "input_height", "grey"},
            "the config", {"decoder"});
  NetConfig config;
  config.kind = KindFromName(Get<std::string>(json, "kind"));
  config.classes = Get<std::vector<std::string>>(json, "classes");
  config.movable = Get<std::vector<std::string>>(json, "movable");
  config.background = Get<std::string>(json, "background");
  const nlohmann::json& backbone = json.at("backbone");
  CheckKeys(backbone, {"last_block", "output_stride", "frozen_blocks"}, "backbone");
  config.backbone.last_block = Get<int>(backbone, "last_block");
  config.backbone.output_stride = Get<int>(backbone, "output_stride");
  config.backbone.frozen_blocks = Get<int>(backbone, "frozen_blocks");
  config.head_channels = Get<int>(json, "head_channels");
  config.head_dilations = Get<std::vector<int>>(json, "head_dilations");
  if (json.contains("decoder")) {
    const nlohmann::json& decoder = json.at("decoder");
    CheckKeys(decoder, {"block", "channels"}, "decoder");
    config.decoder_block = Get<int>(decoder, "block");
    config.decoder_channels = Get<int>(decoder, "channels");
  }
  config.input_width = Get<int>(json, "input_width");
  config.input_height = Get<int>(json, "input_height");
  config.grey = Get<bool>(json, "grey");
  config.Check();
  return config;
}

ClassifierNetImpl::ClassifierNetImpl(const NetConfig& config) : config_(config) {
  config_.Check();
  backbone_ = register_module("backbone", MobileNetV2(config_.backbone));
  class_map_ =
      register_module("class_map", Conv(backbone_->out_channels(), config_.num_classes(), 1));
  InitClassConv(class_map_);
  UseChannelsLast(*this);
}

ClassifierOutput ClassifierNetImpl::forward(torch::Tensor x) {
  ClassifierOutput out;
  out.cams = class_map_->forward(backbone_->forward(x));
  out.logits = out.cams.mean({2, 3});
  return out;
}

SegmenterNetImpl::SegmenterNetImpl(const NetConfig& config) : config_(config) {
  config_.Check();
  backbone_ = register_module("backbone", MobileNetV2(config_.backbone));
  const int in = backbone_->out_channels(), hc = config_.head_channels;
  const int classes = config_.num_classes();
  aspp_ = register_module("aspp", torch::nn::ModuleList());
  std::vector<torch::nn::Conv2d> convs = {Conv(in, hc, 1)};
  for (int d : config_.head_dilations) convs.push_back(Conv(in, hc, 3, d));
  for (torch::nn::Conv2d& conv : convs) {
    InitReluConv(conv);
    aspp_->push_back(torch::nn::Sequential(conv, torch::nn::ReLU()));
  }
  torch::nn::Conv2d pool_conv = Conv(in, hc, 1);
  InitReluConv(pool_conv);
  image_pool_ = register_module(
      "image_pool",
      torch::nn::Sequential(torch::nn::AdaptiveAvgPool2d(torch::nn::AdaptiveAvgPool2dOptions(1)),
                            pool_conv, torch::nn::ReLU()));
  const int branches = static_cast<int>(convs.size()) + 1;
  torch::nn::Conv2d project = Conv(branches * hc, hc, 1);
  InitReluConv(project);
  project_ = register_module("project", torch::nn::Sequential(project, torch::nn::ReLU()));
  int classify_in = hc;
  if (config_.decoder_block > 0) {
    constexpr int kLowLevelChannels = 32;
    torch::nn::Conv2d low = Conv(BlockChannels(config_.decoder_block), kLowLevelChannels, 1);
    InitReluConv(low);
    low_level_ = register_module("low_level", torch::nn::Sequential(low, torch::nn::ReLU()));
    // Depthwise-separable (as MobileNet's own blocks): a full 3x3 conv at stride 4 would cost
    // more than the whole backbone.
    const int cat = hc + kLowLevelChannels, dc = config_.decoder_channels;
    torch::nn::Conv2d depthwise(
        torch::nn::Conv2dOptions(cat, cat, 3).padding(1).groups(cat).bias(true));
    InitReluConv(depthwise);
    torch::nn::Conv2d pointwise = Conv(cat, dc, 1);
    InitReluConv(pointwise);
    decoder_ = register_module("decoder", torch::nn::Sequential(depthwise, torch::nn::ReLU(),
                                                                pointwise, torch::nn::ReLU()));
    classify_in = dc;
  }
  classify_ = register_module("classify", Conv(classify_in, classes, 1));
  InitClassConv(classify_);
  aux_class_map_ = register_module("aux_class_map", Conv(in, classes, 1));
  InitClassConv(aux_class_map_);
  UseChannelsLast(*this);
}

SegmenterOutput SegmenterNetImpl::forward(torch::Tensor x) {
  torch::Tensor low_level;
  const torch::Tensor features = config_.decoder_block > 0
                                     ? backbone_->forward(x, config_.decoder_block, &low_level)
                                     : backbone_->forward(x);
  std::vector<torch::Tensor> branches;
  branches.reserve(aspp_->size() + 1);
  // The 1x1 convs go through ApplyConv (one oneDNN matmul with the ReLU fused at inference, a
  // GEMM in training: not libtorch's single-threaded im2col path); the module layout is
  // unchanged, so older model files load as they were.
  for (const auto& branch : *aspp_) {
    branches.push_back(
        ApplyConv(ConvAt(*branch->as<torch::nn::Sequential>(), 0), features, Activation::kRelu));
  }
  // Image pooling: one vector per image, broadcast over the map.
  branches.push_back(image_pool_->forward(features).expand(
      {features.size(0), config_.head_channels, features.size(2), features.size(3)}));
  SegmenterOutput out;
  torch::Tensor head = ApplyConv(ConvAt(*project_, 0), torch::cat(branches, 1), Activation::kRelu);
  if (config_.decoder_block > 0) {
    head = UpsampleBilinear(head, low_level.size(2), low_level.size(3));
    const torch::Tensor low = ApplyConv(ConvAt(*low_level_, 0), low_level, Activation::kRelu);
    // Depthwise convs are ~20x faster on the channels-last layout; cat may not keep it.
    const torch::Tensor both =
        torch::cat({head, low}, 1).contiguous(torch::MemoryFormat::ChannelsLast);
    head = torch::relu(ConvAt(*decoder_, 0).forward(both));
    head = ApplyConv(ConvAt(*decoder_, 2), head, Activation::kRelu);
  }
  out.logits = ApplyConv(*classify_, head);
  out.class_logits = ApplyConv(*aux_class_map_, features).mean({2, 3});
  return out;
}

torch::Tensor UpsampleBilinear(const torch::Tensor& maps, int64_t height, int64_t width) {
  return torch::nn::functional::interpolate(maps, torch::nn::functional::InterpolateFuncOptions()
                                                      .size(std::vector<int64_t>{height, width})
                                                      .mode(torch::kBilinear)
                                                      .align_corners(false));
}

torch::Tensor ImageToTensor(const cv::Mat& image, cv::Size size, bool grey) {
  if (image.empty() || image.depth() != CV_8U || (image.channels() != 3 && image.channels() != 1)) {
    ThrowInput("ImageToTensor: want a CV_8UC3 or CV_8UC1 image (got type {}, {} x {})",
               image.type(), image.cols, image.rows);
  }
  cv::Mat grey_or_rgb;
  if (image.channels() == 1) {
    grey_or_rgb = image;
  } else if (grey) {
    cv::cvtColor(image, grey_or_rgb, cv::COLOR_BGR2GRAY);
  } else {
    cv::cvtColor(image, grey_or_rgb, cv::COLOR_BGR2RGB);
  }
  cv::Mat resized;
  if (grey_or_rgb.size() == size) {
    resized = grey_or_rgb;
  } else {
    const bool shrink = size.width < image.cols || size.height < image.rows;
    cv::resize(grey_or_rgb, resized, size, 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
  }
  cv::Mat rgb;
  if (resized.channels() == 1) {
    cv::cvtColor(resized, rgb, cv::COLOR_GRAY2RGB);
  } else {
    rgb = resized.isContinuous() ? resized : resized.clone();
  }
  const torch::Tensor bytes = torch::from_blob(rgb.data, {rgb.rows, rgb.cols, 3}, torch::kUInt8);
  // to() copies, so the tensor does not alias the Mat.
  return bytes.permute({2, 0, 1})
      .to(torch::kFloat32)
      .div_(127.5)
      .sub_(1.0)
      .unsqueeze(0)
      .contiguous();
}

torch::Tensor ImageToTensor(const cv::Mat& image, const NetConfig& config) {
  return ImageToTensor(image, {config.input_width, config.input_height}, config.grey);
}

}  // namespace moslam::net
