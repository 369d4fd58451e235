#include "moslam/net/mobilenet_v2.h"

#include <array>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/script.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::net {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

constexpr const char* kWeights =
    "models/mobilenet_v2_imagenet/mobilenet_v2_imagenet.torchscript.pt";

// Copies every parameter of `from` into `to` (same architecture, possibly other strides).
void CopyWeights(MobileNetV2& from, MobileNetV2& to) {
  torch::NoGradGuard no_grad;
  auto source = from->named_parameters();
  for (auto& p : to->named_parameters()) p.value().copy_(source[p.key()]);
}

TEST(MobileNetV2, BlockTable) {
  EXPECT_EQ(BlockChannels(0), 32);
  EXPECT_EQ(BlockChannels(1), 16);
  EXPECT_EQ(BlockChannels(13), 96);
  EXPECT_EQ(BlockChannels(17), 320);
  EXPECT_EQ(BlockChannels(18), 1280);
  EXPECT_EQ(BlockStride(0), 2);
  EXPECT_EQ(BlockStride(3), 4);
  EXPECT_EQ(BlockStride(6), 8);
  EXPECT_EQ(BlockStride(13), 16);
  EXPECT_EQ(BlockStride(14), 32);
  EXPECT_EQ(BlockStride(18), 32);
}

TEST(MobileNetV2, OptionsCheckNamesTheField) {
  BackboneOptions options;
  options.last_block = 19;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("last_block"));
  options = {};
  options.output_stride = 4;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("output_stride"));
  options = {};
  options.output_stride = 32;  // block 13 ends at stride 16
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("output_stride"));
  options = {};
  options.frozen_blocks = 15;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("frozen_blocks"));
}

struct ShapeCase {
  int last_block, output_stride, channels;
};

TEST(MobileNetV2, OutputShapeFollowsLastBlockAndStride) {
  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::rand({2, 3, 100, 70}) * 2 - 1;
  for (const ShapeCase& c : std::vector<ShapeCase>{
           {13, 8, 96}, {13, 16, 96}, {17, 8, 320}, {17, 16, 320}, {17, 32, 320}, {18, 32, 1280}}) {
    BackboneOptions options;
    options.last_block = c.last_block;
    options.output_stride = c.output_stride;
    MobileNetV2 net(options);
    EXPECT_EQ(net->out_channels(), c.channels);
    EXPECT_EQ(net->output_stride(), c.output_stride);
    const torch::Tensor y = net->forward(x);
    const int64_t h = (100 + c.output_stride - 1) / c.output_stride;
    const int64_t w = (70 + c.output_stride - 1) / c.output_stride;
    EXPECT_EQ(y.sizes(), (std::vector<int64_t>{2, c.channels, h, w}))
        << "last_block " << c.last_block << " output_stride " << c.output_stride;
  }
}

// Dilation instead of stride (the "a trous" algorithm) computes the same function on a denser
// grid: every k-th output of the dilated network is the strided network's output.
TEST(MobileNetV2, DilatedBackboneIsTheStridedOneOnADenserGrid) {
  for (const std::array<int, 3>& c : {std::array<int, 3>{17, 32, 16}, {17, 32, 8}, {13, 16, 8}}) {
    torch::manual_seed(3);
    BackboneOptions coarse_options;
    coarse_options.last_block = c[0];
    coarse_options.output_stride = c[1];
    BackboneOptions fine_options = coarse_options;
    fine_options.output_stride = c[2];
    MobileNetV2 coarse(coarse_options), fine(fine_options);
    CopyWeights(coarse, fine);
    torch::NoGradGuard no_grad;
    const torch::Tensor x = torch::rand({1, 3, 90, 130}) * 2 - 1;
    const torch::Tensor y_coarse = coarse->forward(x);
    const int64_t k = c[1] / c[2];
    using torch::indexing::None;
    using torch::indexing::Slice;
    const torch::Tensor sub = fine->forward(x).index({"...", Slice(0, None, k), Slice(0, None, k)});
    ASSERT_EQ(sub.sizes(), y_coarse.sizes());
    const double scale = y_coarse.abs().max().item<double>();
    ASSERT_GT(scale, 1e-3) << "activations vanished: the test would compare noise";
    EXPECT_LT((sub - y_coarse).abs().max().item<double>(), 1e-4 * scale)
        << "last_block " << c[0] << ", output stride " << c[2] << " vs " << c[1];
  }
}

TEST(MobileNetV2, FrozenBlocksGetNoGradient) {
  BackboneOptions options;
  options.last_block = 8;
  options.output_stride = 16;
  options.frozen_blocks = 4;
  MobileNetV2 net(options);
  net->forward(torch::rand({1, 3, 48, 48})).square().sum().backward();
  int frozen = 0, trained = 0;
  for (const auto& p : net->named_parameters()) {
    const int block = std::stoi(p.key().substr(p.key().find('.') + 1));
    if (block < options.frozen_blocks) {
      EXPECT_FALSE(p.value().requires_grad()) << p.key();
      EXPECT_FALSE(p.value().grad().defined()) << p.key();
      ++frozen;
    } else {
      ASSERT_TRUE(p.value().grad().defined()) << p.key();
      EXPECT_GT(p.value().grad().abs().sum().item<double>(), 0.0) << p.key();
      ++trained;
    }
  }
  EXPECT_GT(frozen, 0);
  EXPECT_GT(trained, 0);
}

TEST(MobileNetV2, MissingWeightsFileIsAnInputError) {
  MobileNetV2 net;
  EXPECT_THAT(ErrorOf([&] { LoadImageNetWeights("/nonexistent/weights.pt", net); }),
              HasSubstr("/nonexistent/weights.pt"));
}

// The folded backbone plus torchvision's classifier (global mean, classifier.1) reproduces the
// TorchScript model's ImageNet logits.
TEST(MobileNetV2, ImageNetLogitsMatchTheTorchScriptModel) {
  MOSLAM_SHARED_OR_SKIP(path, kWeights);
  torch::jit::Module reference = torch::jit::load(path);
  reference.eval();
  BackboneOptions options;
  options.last_block = 18;
  options.output_stride = 32;
  MobileNetV2 net(options);
  LoadImageNetWeights(path, net);
  torch::nn::Linear classifier(1280, 1001);
  torch::NoGradGuard no_grad;
  for (const auto& p : reference.named_parameters()) {
    if (p.name == "classifier.1.weight") classifier->weight.copy_(p.value);
    if (p.name == "classifier.1.bias") classifier->bias.copy_(p.value);
  }
  torch::manual_seed(7);
  const torch::Tensor x = torch::rand({2, 3, 224, 224}) * 2 - 1;
  const torch::Tensor expected = reference.forward({x}).toTensor();
  const torch::Tensor logits = classifier->forward(net->forward(x).mean({2, 3}));
  ASSERT_EQ(logits.sizes(), expected.sizes());
  const double scale = expected.abs().max().item<double>();
  EXPECT_LT((logits - expected).abs().max().item<double>(), 1e-3 * scale);
  EXPECT_TRUE(torch::equal(logits.argmax(1), expected.argmax(1)));
}

TEST(MobileNetV2, ImageNetWeightsOfATruncatedDilatedBackbone) {
  MOSLAM_SHARED_OR_SKIP(path, kWeights);
  BackboneOptions options;
  options.last_block = 13;
  options.output_stride = 8;
  options.frozen_blocks = 3;
  MobileNetV2 net(options);
  LoadImageNetWeights(path, net);
  for (const auto& p : net->named_parameters()) {
    const int block = std::stoi(p.key().substr(p.key().find('.') + 1));
    EXPECT_EQ(p.value().requires_grad(), block >= 3) << p.key();
  }
  torch::NoGradGuard no_grad;
  const torch::Tensor y = net->forward(torch::zeros({1, 3, 64, 64}));
  EXPECT_EQ(y.sizes(), (std::vector<int64_t>{1, 96, 8, 8}));
  EXPECT_TRUE(torch::isfinite(y).all().item<bool>());
}

}  // namespace
}  // namespace moslam::net
