#include "moslam/net/op_counter.h"

#include <optional>

#include <gtest/gtest.h>
#include <torch/torch.h>

#include "moslam/net/mobilenet_v2.h"

namespace moslam::net {
namespace {

namespace F = torch::nn::functional;

TEST(OpCounter, CountsEachKindOfLayerExactly) {
  c10::InferenceMode inference;
  const torch::Tensor x = torch::rand({1, 3, 32, 32});
  const torch::Tensor dense_w = torch::rand({8, 3, 3, 3});
  const torch::Tensor depthwise_w = torch::rand({8, 1, 3, 3});
  const torch::Tensor pointwise_w = torch::rand({4, 8, 1, 1});
  const torch::Tensor gemm_b = torch::rand({8, 16});
  const torch::Tensor gemm_bias = torch::rand({16});
  OpCounter counter;
  // 3x3, stride 2: 8 x 16 x 16 outputs of 3 x 3 x 3 multiply-adds each.
  const torch::Tensor a = F::conv2d(x, dense_w, F::Conv2dFuncOptions().stride(2).padding(1));
  // Depthwise 3x3: 8 x 16 x 16 outputs of 9 each.
  const torch::Tensor b = F::conv2d(a, depthwise_w, F::Conv2dFuncOptions().padding(1).groups(8));
  // 1x1 convolution: 4 x 16 x 16 outputs of 8 each.
  const torch::Tensor c = F::conv2d(b, pointwise_w);
  // GEMM {256, 8} x {8, 16}: 256 x 16 outputs of 8 each.
  const torch::Tensor rows = b.permute({0, 2, 3, 1}).reshape({256, 8});
  const torch::Tensor d = torch::addmm(gemm_bias, rows, gemm_b);
  ASSERT_EQ(c.numel(), 4 * 16 * 16);
  ASSERT_EQ(d.numel(), 256 * 16);

  const OpCount& count = counter.count();
  ASSERT_EQ(count.by_kind.size(), 4u);
  EXPECT_EQ(count.by_kind.at(OpKind::kDenseConv).calls, 1);
  EXPECT_DOUBLE_EQ(count.by_kind.at(OpKind::kDenseConv).macs, 8.0 * 16 * 16 * 27);
  EXPECT_DOUBLE_EQ(count.by_kind.at(OpKind::kDepthwise).macs, 8.0 * 16 * 16 * 9);
  EXPECT_DOUBLE_EQ(count.by_kind.at(OpKind::kPointwise).macs, 4.0 * 16 * 16 * 8);
  EXPECT_DOUBLE_EQ(count.by_kind.at(OpKind::kGemm).macs, 256.0 * 16 * 8);
  EXPECT_EQ(count.Total().calls, 4);
  EXPECT_DOUBLE_EQ(count.Total().macs, 8.0 * 256 * 27 + 8.0 * 256 * 9 + 4.0 * 256 * 8 + 4096 * 8);
  for (const auto& [kind, stats] : count.by_kind) {
    EXPECT_GE(stats.ms, 0.0) << ToString(kind);
  }
}

TEST(OpCounter, StopsCountingWhenDestroyedAndCountsOnlyItsThread) {
  c10::InferenceMode inference;
  const torch::Tensor x = torch::rand({1, 4, 8, 8});
  const torch::Tensor w = torch::rand({4, 4, 3, 3});
  {
    OpCounter counter;
    F::conv2d(x, w);
    EXPECT_EQ(counter.count().Total().calls, 1);
    counter.Reset();
    EXPECT_EQ(counter.count().Total().calls, 0);
  }
  OpCounter counter;  // a new one starts from nothing, and the first left no callback behind
  F::conv2d(x, w);
  F::conv2d(x, w);
  EXPECT_EQ(counter.count().Total().calls, 2);
  EXPECT_DOUBLE_EQ(counter.count().Total().macs, 2.0 * 4 * 6 * 6 * 36);
}

// The backbone's own layers as its forward runs them: at inference every 1x1 convolution with a
// bias is one fused oneDNN matmul (fused_pointwise.h), in training a libtorch GEMM
// (mobilenet_v2.cc's Pointwise); the 3x3 ones stay convolutions; and the multiply-adds add up to
// the layers' analytic count (Sandler et al. 2018, Table 2: the stem and blocks 1-4 on a 64 x 64
// input).
TEST(OpCounter, SeesTheBackbonesLayersOnce) {
  torch::manual_seed(0);
  BackboneOptions options;
  options.last_block = 4;  // natural stride 8
  options.output_stride = 8;
  MobileNetV2 backbone(options);
  const torch::Tensor x = torch::rand({1, 3, 64, 64});
  // Pixels at strides 2, 4 and 8.
  const double p2 = 32 * 32, p4 = 16 * 16, p8 = 8 * 8;
  // Stem: 3x3 stride 2, 3 -> 32.
  const double dense = p2 * 32 * 27;
  // Depthwise 3x3 at each block's output resolution: block 1 (32 channels), block 2 (96,
  // stride 2), block 3 (144), block 4 (144, stride 2).
  const double depthwise = 9 * (p2 * 32 + p4 * 96 + p4 * 144 + p8 * 144);
  // 1x1: block 1 32 -> 16; block 2 16 -> 96, 96 -> 24; block 3 24 -> 144, 144 -> 24; block 4
  // 24 -> 144 (before its stride), 144 -> 32.
  const double pointwise = p2 * 32 * 16 + p2 * 16 * 96 + p4 * 96 * 24 + 2 * p4 * 24 * 144 +
                           p4 * 24 * 144 + p8 * 144 * 32;
  for (const bool inference : {true, false}) {
    SCOPED_TRACE(inference ? "inference" : "training");
    std::optional<c10::InferenceMode> mode;
    if (inference) mode.emplace();
    backbone->train(!inference);
    OpCounter counter;
    backbone->forward(x);
    const OpCount& count = counter.count();
    const OpKind one_by_one = inference ? OpKind::kPointwise : OpKind::kGemm;
    EXPECT_DOUBLE_EQ(count.by_kind.at(OpKind::kDenseConv).macs, dense);
    EXPECT_DOUBLE_EQ(count.by_kind.at(OpKind::kDepthwise).macs, depthwise);
    EXPECT_DOUBLE_EQ(count.by_kind.at(one_by_one).macs, pointwise);
    EXPECT_EQ(count.by_kind.at(one_by_one).calls, 7);
    EXPECT_EQ(count.by_kind.size(), 3u);
  }
}

}  // namespace
}  // namespace moslam::net
