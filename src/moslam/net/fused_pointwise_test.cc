#include "moslam/net/fused_pointwise.h"

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "moslam/net/mobilenet_v2.h"

namespace moslam::net {
namespace {

torch::Tensor Reference(const torch::Tensor& x, const torch::Tensor& weight,
                        const torch::Tensor& bias, Activation activation) {
  const torch::Tensor y = torch::nn::functional::conv2d(
      x, weight, torch::nn::functional::Conv2dFuncOptions().bias(bias));
  switch (activation) {
    case Activation::kNone:
      return y;
    case Activation::kRelu:
      return torch::relu(y);
    case Activation::kRelu6:
      return torch::clamp(y, 0.0, 6.0);
  }
  return y;
}

// The fused matmul equals libtorch's convolution followed by the activation, for each activation,
// both memory formats of input and weight, batches and shapes with odd sizes.
TEST(FusedPointwise, EqualsTheConvolutionAndActivation) {
  torch::manual_seed(3);
  c10::InferenceMode inference;
  for (const auto& [n, c, out, h, w] : std::vector<std::array<int64_t, 5>>{
           {1, 16, 96, 30, 40}, {2, 7, 5, 3, 9}, {1, 384, 64, 19, 25}, {1, 3, 1, 1, 1}}) {
    const torch::Tensor x = torch::randn({n, c, h, w}) * 3;
    const torch::Tensor weight = torch::randn({out, c, 1, 1});
    const torch::Tensor bias = torch::randn({out});
    for (const Activation activation : {Activation::kNone, Activation::kRelu, Activation::kRelu6}) {
      const torch::Tensor expected = Reference(x, weight, bias, activation);
      for (const auto format :
           {torch::MemoryFormat::Contiguous, torch::MemoryFormat::ChannelsLast}) {
        const torch::Tensor y =
            FusedPointwise(x.contiguous(format), weight.contiguous(format), bias, activation);
        ASSERT_EQ(y.sizes(), expected.sizes());
        EXPECT_TRUE(y.is_contiguous(torch::MemoryFormat::ChannelsLast));
        EXPECT_TRUE(torch::allclose(y, expected, 1e-4, 1e-4))
            << "n " << n << " c " << c << " out " << out << ": largest difference "
            << (y - expected).abs().max().item<float>();
      }
    }
  }
}

TEST(FusedPointwise, AppliesOnlyWhereNoGradientIsWantedAndTheShapesFit) {
  const torch::Tensor x = torch::rand({1, 4, 5, 5});
  const torch::Tensor weight = torch::rand({3, 4, 1, 1});
  const torch::Tensor bias = torch::rand({3});
  EXPECT_TRUE(FusedPointwiseApplies(x, weight, bias));
  EXPECT_FALSE(FusedPointwiseApplies(x, weight.clone().requires_grad_(), bias));
  {
    torch::NoGradGuard no_grad;  // evaluation of a model being trained: no gradient wanted
    EXPECT_TRUE(FusedPointwiseApplies(x, weight.clone().requires_grad_(), bias));
  }
  EXPECT_FALSE(FusedPointwiseApplies(x, torch::rand({3, 4, 3, 3}), bias));  // not 1x1
  EXPECT_FALSE(FusedPointwiseApplies(x, torch::rand({3, 5, 1, 1}), bias));  // channels
  EXPECT_FALSE(FusedPointwiseApplies(x, weight, torch::rand({4})));         // bias
  EXPECT_FALSE(FusedPointwiseApplies(x.to(torch::kDouble), weight, bias));  // dtype
  EXPECT_FALSE(FusedPointwiseApplies(x.view({4, 5, 5}), weight, bias));     // 3-D
}

// ApplyConv takes the fused path at inference and libtorch's operators in training, with the
// same result, and gradients still flow in training.
TEST(FusedPointwise, ApplyConvGivesTheSameOutputInTrainingAndInference) {
  torch::manual_seed(4);
  torch::nn::Conv2d conv(torch::nn::Conv2dOptions(12, 20, 1));
  const torch::Tensor x =
      torch::randn({1, 12, 9, 11}).contiguous(torch::MemoryFormat::ChannelsLast);
  const torch::Tensor trained = ApplyConv(*conv, x, Activation::kRelu6);
  ASSERT_TRUE(trained.requires_grad());
  torch::Tensor inferred;
  {
    c10::InferenceMode inference;
    inferred = ApplyConv(*conv, x, Activation::kRelu6);
  }
  EXPECT_FALSE(inferred.requires_grad());
  EXPECT_TRUE(torch::allclose(trained.detach(), inferred, 1e-5, 1e-5));
  trained.sum().backward();
  EXPECT_TRUE(conv->weight.grad().defined());
  EXPECT_GT(conv->weight.grad().abs().sum().item<float>(), 0.0f);
}

}  // namespace
}  // namespace moslam::net
