#include "moslam/net/mobilenet_v2.h"

#include <algorithm>
#include <array>
#include <filesystem>
#include <vector>

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <spdlog/spdlog.h>
#include <torch/script.h>

#include "moslam/semantic/model_card.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::net {
namespace {

// torchvision's inverted residual settings (Sandler et al. 2018, Table 2): expansion t, output
// channels c, repeats n, first stride s.
struct StageSetting {
  int t, c, n, s;
};
constexpr std::array<StageSetting, 7> kStages = {{{1, 16, 1, 1},
                                                  {6, 24, 2, 2},
                                                  {6, 32, 3, 2},
                                                  {6, 64, 4, 2},
                                                  {6, 96, 3, 1},
                                                  {6, 160, 3, 2},
                                                  {6, 320, 1, 1}}};
constexpr int kStemChannels = 32;
constexpr int kLastChannels = 1280;
constexpr int kNumBlocks = 19;  // features.0 .. features.18

struct BlockSpec {
  int in = 0, out = 0, expansion = 1, stride = 1;
};

std::vector<BlockSpec> BlockSpecs() {
  std::vector<BlockSpec> specs;
  specs.push_back({3, kStemChannels, 1, 2});
  int in = kStemChannels;
  for (const StageSetting& stage : kStages) {
    for (int i = 0; i < stage.n; ++i) {
      specs.push_back({in, stage.c, stage.t, i == 0 ? stage.s : 1});
      in = stage.c;
    }
  }
  specs.push_back({in, kLastChannels, 1, 1});
  return specs;
}

const std::vector<BlockSpec>& Specs() {
  static const std::vector<BlockSpec> specs = BlockSpecs();
  return specs;
}

torch::nn::Conv2d MakeConv(int in, int out, int kernel, int stride, int dilation, int groups) {
  const int padding = kernel == 3 ? dilation : 0;
  return torch::nn::Conv2d(torch::nn::Conv2dOptions(in, out, kernel)
                               .stride(stride)
                               .padding(padding)
                               .dilation(dilation)
                               .groups(groups)
                               .bias(true));
}

// One torchvision block with BatchNorm folded into conv biases. Convs are registered as c0, c1,
// c2 in forward order; TorchvisionNames() says where each one's weights live in torchvision.
class BlockImpl : public torch::nn::Module {
 public:
  BlockImpl(int index, const BlockSpec& spec, int stride, int dilation) {
    if (index == 0) {  // stem: 3x3 conv, ReLU6
      Add(MakeConv(spec.in, spec.out, 3, stride, 1, 1), true);
    } else if (index == kNumBlocks - 1) {  // final 1x1 conv, ReLU6
      Add(MakeConv(spec.in, spec.out, 1, 1, 1, 1), true);
    } else {
      const int hidden = spec.in * spec.expansion;
      if (spec.expansion != 1) Add(MakeConv(spec.in, hidden, 1, 1, 1, 1), true);
      Add(MakeConv(hidden, hidden, 3, stride, dilation, hidden), true);
      Add(MakeConv(hidden, spec.out, 1, 1, 1, 1), false);  // linear bottleneck
      // torchvision decides the shortcut by the natural stride; a dilated block keeps it off
      // so that the pretrained function is unchanged.
      residual_ = spec.stride == 1 && spec.in == spec.out;
    }
  }

  torch::Tensor forward(torch::Tensor x) {
    torch::Tensor y = x;
    for (size_t i = 0; i < convs_.size(); ++i) {
      torch::nn::Conv2d& conv = convs_[i];
      y = ApplyConv(*conv, y, relu_[i] ? Activation::kRelu6 : Activation::kNone);
    }
    return residual_ ? y + x : y;
  }

  const std::vector<torch::nn::Conv2d>& convs() const { return convs_; }

 private:
  void Add(torch::nn::Conv2d conv, bool relu) {
    convs_.push_back(register_module("c" + std::to_string(convs_.size()), conv));
    relu_.push_back(relu);
  }

  std::vector<torch::nn::Conv2d> convs_;
  std::vector<bool> relu_;
  bool residual_ = false;
};
TORCH_MODULE(Block);

// (conv, batchnorm) module paths of block `index`'s convs c0, c1, ... relative to torchvision's
// features.<index> (ConvBNReLU: 0 and 1; InvertedResidual: conv.K...).
std::vector<std::pair<std::string, std::string>> TorchvisionNames(int index) {
  if (index == 0 || index == kNumBlocks - 1) return {{"0", "1"}};
  if (Specs()[index].expansion == 1) return {{"conv.0.0", "conv.0.1"}, {"conv.1", "conv.2"}};
  return {{"conv.0.0", "conv.0.1"}, {"conv.1.0", "conv.1.1"}, {"conv.2", "conv.3"}};
}

// He et al. 2015 initialization by fan-in (a depthwise conv's fan-in is its 3x3 window), which
// keeps activations at unit scale without BatchNorm; the ImageNet weights normally replace it.
void InitializeConv(torch::nn::Conv2d& conv) {
  torch::NoGradGuard no_grad;
  torch::nn::init::kaiming_normal_(conv->weight, 0.0, torch::kFanIn, torch::kReLU);
  conv->bias.zero_();
}

torch::Tensor Find(const torch::OrderedDict<std::string, torch::Tensor>& tensors,
                   const std::string& name, const std::string& path) {
  const torch::Tensor* found = tensors.find(name);
  if (found == nullptr) ThrowInFile(path, fmt::format("no tensor '{}'", name));
  return *found;
}

void CheckShape(const torch::Tensor& tensor, at::IntArrayRef expected, const std::string& name,
                const std::string& path) {
  if (tensor.sizes() != expected) {
    ThrowInFile(path, fmt::format("tensor '{}' has shape {}, the network expects {}", name,
                                  fmt::join(tensor.sizes(), "x"), fmt::join(expected, "x")));
  }
}

}  // namespace

// libtorch 1.13 sends single-threaded 1x1 convs to its slow im2col path, which also converts
// layouts back and forth; the GEMM is the same arithmetic without those copies.
torch::Tensor Pointwise(const torch::Tensor& x, const torch::Tensor& weight,
                        const torch::Tensor& bias) {
  const int64_t n = x.size(0), c = x.size(1), h = x.size(2), w = x.size(3);
  const torch::Tensor rows = x.permute({0, 2, 3, 1}).reshape({n * h * w, c});
  const torch::Tensor y = torch::addmm(bias, rows, weight.view({weight.size(0), c}).t());
  return y.view({n, h, w, weight.size(0)}).permute({0, 3, 1, 2});
}

torch::Tensor ApplyConv(torch::nn::Conv2dImpl& conv, const torch::Tensor& x,
                        Activation activation) {
  const auto& o = conv.options;
  const bool pointwise = o.kernel_size()->at(0) == 1 && o.kernel_size()->at(1) == 1 &&
                         o.stride()->at(0) == 1 && o.stride()->at(1) == 1 && o.groups() == 1 &&
                         conv.bias.defined();
  if (pointwise && FusedPointwiseApplies(x, conv.weight, conv.bias)) {
    return FusedPointwise(x, conv.weight, conv.bias, activation);
  }
  torch::Tensor y = pointwise ? Pointwise(x, conv.weight, conv.bias) : conv.forward(x);
  switch (activation) {
    case Activation::kNone:
      return y;
    case Activation::kRelu:
      return torch::relu(y);
    case Activation::kRelu6:
      return torch::hardtanh_(y, 0.0, 6.0);  // in place; autograd keeps the result
  }
  return y;
}

void BackboneOptions::Check() const {
  if (last_block < 1 || last_block > 18) {
    ThrowInput("backbone.last_block must be in 1..18 (is {})", last_block);
  }
  if (output_stride != 8 && output_stride != 16 && output_stride != 32) {
    ThrowInput("backbone.output_stride must be 8, 16 or 32 (is {})", output_stride);
  }
  if (output_stride > BlockStride(last_block)) {
    ThrowInput("backbone.output_stride {} exceeds the natural stride {} of last_block {}",
               output_stride, BlockStride(last_block), last_block);
  }
  if (frozen_blocks < 0 || frozen_blocks > last_block + 1) {
    ThrowInput("backbone.frozen_blocks must be in 0..last_block+1 = 0..{} (is {})", last_block + 1,
               frozen_blocks);
  }
}

int BlockChannels(int block) {
  if (block < 0 || block >= kNumBlocks) ThrowInput("MobileNetV2 block {} is not in 0..18", block);
  return Specs()[block].out;
}

int BlockStride(int block) {
  if (block < 0 || block >= kNumBlocks) ThrowInput("MobileNetV2 block {} is not in 0..18", block);
  int stride = 1;
  for (int i = 0; i <= block; ++i) stride *= Specs()[i].stride;
  return stride;
}

MobileNetV2Impl::MobileNetV2Impl(const BackboneOptions& options) : options_(options) {
  options_.Check();
  blocks_ = register_module("blocks", torch::nn::Sequential());
  // DeepLab's output-stride rule (Chen et al. 2017; as in TF-slim and torchvision's ResNet): the
  // first block that would go below the requested resolution keeps stride 1 with the current
  // dilation, and every later 3x3 conv is dilated by the accumulated stride.
  int stride = 1, dilation = 1;
  for (int i = 0; i <= options_.last_block; ++i) {
    const BlockSpec& spec = Specs()[i];
    const int block_dilation = dilation;
    int block_stride = spec.stride;
    if (stride * spec.stride > options_.output_stride) {
      dilation *= spec.stride;
      block_stride = 1;
    } else {
      stride *= spec.stride;
    }
    Block block(i, spec, block_stride, block_dilation);
    for (torch::nn::Conv2d conv : block->convs()) InitializeConv(conv);
    blocks_->push_back(block);
  }
  UseChannelsLast(*this);
  ApplyFreezing();
}

torch::Tensor MobileNetV2Impl::forward(torch::Tensor x) { return Run(x, -1, nullptr); }

torch::Tensor MobileNetV2Impl::forward(torch::Tensor x, int tap, torch::Tensor* tapped) {
  MOSLAM_CHECK(tap >= 0 && tap <= options_.last_block && tapped != nullptr);
  return Run(x, tap, tapped);
}

torch::Tensor MobileNetV2Impl::Run(const torch::Tensor& x, int tap, torch::Tensor* tapped) {
  if (x.dim() != 4 || x.size(1) != 3) {
    ThrowInput("MobileNetV2 wants N x 3 x H x W input (got {} dimensions)", x.dim());
  }
  torch::Tensor y = x.contiguous(torch::MemoryFormat::ChannelsLast);
  for (size_t i = 0; i < blocks_->size(); ++i) {
    y = blocks_->ptr(i)->as<BlockImpl>()->forward(y);
    if (static_cast<int>(i) == tap) *tapped = y;
  }
  return y;
}

int MobileNetV2Impl::out_channels() const { return BlockChannels(options_.last_block); }

int MobileNetV2Impl::output_stride() const {
  return std::min(options_.output_stride, BlockStride(options_.last_block));
}

void MobileNetV2Impl::ApplyFreezing() {
  for (size_t i = 0; i < blocks_->size(); ++i) {
    const bool train = static_cast<int>(i) >= options_.frozen_blocks;
    for (torch::Tensor& p : blocks_->ptr(i)->parameters()) p.set_requires_grad(train);
  }
}

void LoadImageNetWeights(const std::string& torchscript_path, MobileNetV2& backbone) {
  if (!std::filesystem::is_regular_file(torchscript_path)) {
    ThrowInFile(torchscript_path, "ImageNet weights not found");
  }
  torch::jit::Module module;
  try {
    module = torch::jit::load(torchscript_path, torch::kCPU);
  } catch (const c10::Error& e) {
    ThrowInFile(torchscript_path,
                fmt::format("not a TorchScript file: {}", e.what_without_backtrace()));
  }
  torch::OrderedDict<std::string, torch::Tensor> tensors;
  for (const auto& p : module.named_parameters()) tensors.insert(p.name, p.value);
  for (const auto& b : module.named_buffers()) tensors.insert(b.name, b.value);

  // BatchNorm folding (Jacob et al. 2018): BN(conv(x)) = conv'(x) with
  // w' = w * gamma / sqrt(var + eps), b' = beta - mean * gamma / sqrt(var + eps).
  constexpr double kEps = 1e-5;
  torch::NoGradGuard no_grad;
  auto named = backbone->named_parameters();
  int copied = 0;
  for (int i = 0; i <= backbone->options().last_block; ++i) {
    const std::string ours = fmt::format("blocks.{}.", i);
    const std::string theirs = fmt::format("features.{}.", i);
    const auto names = TorchvisionNames(i);
    for (size_t k = 0; k < names.size(); ++k) {
      const std::string conv = theirs + names[k].first, bn = theirs + names[k].second;
      torch::Tensor& weight = named[ours + "c" + std::to_string(k) + ".weight"];
      torch::Tensor& bias = named[ours + "c" + std::to_string(k) + ".bias"];
      const torch::Tensor w = Find(tensors, conv + ".weight", torchscript_path);
      CheckShape(w, weight.sizes(), conv + ".weight", torchscript_path);
      const int64_t out = weight.size(0);
      std::array<torch::Tensor, 4> stats;
      const std::array<const char*, 4> keys = {"weight", "bias", "running_mean", "running_var"};
      for (size_t j = 0; j < keys.size(); ++j) {
        const std::string name = bn + "." + keys[j];
        stats[j] = Find(tensors, name, torchscript_path).to(torch::kFloat64);
        CheckShape(stats[j], {out}, name, torchscript_path);
      }
      const torch::Tensor scale = stats[0] / torch::sqrt(stats[3] + kEps);
      weight.copy_(w.to(torch::kFloat64) * scale.view({out, 1, 1, 1}));
      bias.copy_(stats[1] - stats[2] * scale);
      ++copied;
    }
  }
  backbone->ApplyFreezing();
  spdlog::debug("MobileNetV2: {} convs loaded from {}", copied, torchscript_path);
}

void UseChannelsLast(torch::nn::Module& module) {
  torch::NoGradGuard no_grad;
  for (torch::Tensor& p : module.parameters()) {
    if (p.dim() == 4) p.set_data(p.contiguous(torch::MemoryFormat::ChannelsLast));
  }
}

std::string DefaultImageNetWeightsPath() {
  return semantic::SharedRoot() +
         "/models/mobilenet_v2_imagenet/mobilenet_v2_imagenet.torchscript.pt";
}

}  // namespace moslam::net
