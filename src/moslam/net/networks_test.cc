#include "moslam/net/networks.h"

#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "moslam/testing/error_of.h"

namespace moslam::net {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

// A small network that runs in milliseconds (also under ASan).
NetConfig SmallConfig(NetKind kind) {
  NetConfig config;
  config.kind = kind;
  config.classes = {"background", "car", "person", "tree"};
  config.movable = {"car", "person"};
  config.background = "background";
  config.backbone.last_block = 6;
  config.backbone.output_stride = 8;
  config.head_channels = 8;
  config.head_dilations = {2, 3};
  config.input_width = 64;
  config.input_height = 48;
  return config;
}

// Every parameter is reached by the loss (nothing registered but unused).
void ExpectEveryParameterHasAGradient(const torch::nn::Module& net) {
  for (const auto& p : net.named_parameters()) {
    EXPECT_TRUE(p.value().grad().defined()) << p.key();
  }
}

TEST(NetConfig, JsonRoundTrip) {
  NetConfig config = SmallConfig(NetKind::kSegmenter);
  config.grey = true;
  config.backbone.frozen_blocks = 2;
  const NetConfig back = NetConfigFromJson(ToJson(config));
  EXPECT_EQ(back.kind, NetKind::kSegmenter);
  EXPECT_EQ(back.classes, config.classes);
  EXPECT_EQ(back.movable, config.movable);
  EXPECT_EQ(back.background, "background");
  EXPECT_EQ(back.backbone.last_block, 6);
  EXPECT_EQ(back.backbone.output_stride, 8);
  EXPECT_EQ(back.backbone.frozen_blocks, 2);
  EXPECT_EQ(back.head_channels, 8);
  EXPECT_EQ(back.head_dilations, (std::vector<int>{2, 3}));
  EXPECT_EQ(back.input_width, 64);
  EXPECT_EQ(back.input_height, 48);
  EXPECT_TRUE(back.grey);
  EXPECT_EQ(ToJson(back), ToJson(config));
  EXPECT_EQ(back.BackgroundIndex(), 0);
}

TEST(NetConfig, DecoderRoundTripsAndOldConfigsStayAsTheyWere) {
  NetConfig config = SmallConfig(NetKind::kSegmenter);
  EXPECT_FALSE(ToJson(config).contains("decoder"));  // files of decoder-less nets unchanged
  config.decoder_block = 3;
  config.decoder_channels = 12;
  const nlohmann::json json = ToJson(config);
  ASSERT_TRUE(json.contains("decoder"));
  const NetConfig back = NetConfigFromJson(json);
  EXPECT_EQ(back.decoder_block, 3);
  EXPECT_EQ(back.decoder_channels, 12);
  nlohmann::json bad = json;
  bad["decoder"]["chanels"] = 3;
  EXPECT_THAT(ErrorOf([&] { NetConfigFromJson(bad); }), HasSubstr("'chanels'"));
}

TEST(NetConfig, UnknownMissingAndBadKeysAreNamed) {
  nlohmann::json json = ToJson(SmallConfig(NetKind::kClassifier));
  json["head_channel"] = 3;
  EXPECT_THAT(ErrorOf([&] { NetConfigFromJson(json); }), HasSubstr("'head_channel'"));
  json = ToJson(SmallConfig(NetKind::kClassifier));
  json["backbone"]["stride"] = 3;
  EXPECT_THAT(ErrorOf([&] { NetConfigFromJson(json); }), HasSubstr("'stride'"));
  json = ToJson(SmallConfig(NetKind::kClassifier));
  json.erase("grey");
  EXPECT_THAT(ErrorOf([&] { NetConfigFromJson(json); }), HasSubstr("'grey'"));
  json = ToJson(SmallConfig(NetKind::kClassifier));
  json["input_width"] = "wide";
  EXPECT_THAT(ErrorOf([&] { NetConfigFromJson(json); }), HasSubstr("input_width"));
  json = ToJson(SmallConfig(NetKind::kClassifier));
  json["kind"] = "detector";
  EXPECT_THAT(ErrorOf([&] { NetConfigFromJson(json); }), HasSubstr("kind"));
}

TEST(NetConfig, CheckNamesTheField) {
  NetConfig config = SmallConfig(NetKind::kClassifier);
  config.movable = {"bus"};
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("movable"));
  config = SmallConfig(NetKind::kClassifier);
  config.background = "sky";
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("background"));
  config = SmallConfig(NetKind::kClassifier);
  config.classes.push_back("car");
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("classes"));
  config = SmallConfig(NetKind::kClassifier);
  config.head_dilations = {0};
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("head_dilations"));
  config = SmallConfig(NetKind::kClassifier);
  config.backbone.output_stride = 32;
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("output_stride"));
  config = SmallConfig(NetKind::kSegmenter);
  config.decoder_block = 6;  // stride 8: no finer than the backbone's output
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("decoder_block"));
  config.decoder_block = -1;
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("decoder_block"));
  config.decoder_block = 3;
  config.decoder_channels = 0;
  EXPECT_THAT(ErrorOf([&] { config.Check(); }), HasSubstr("decoder_channels"));
  config = SmallConfig(NetKind::kClassifier);
  config.background.clear();
  EXPECT_EQ(config.BackgroundIndex(), -1);
}

TEST(ClassifierNet, LogitsAreTheSpatialMeanOfTheCams) {
  ClassifierNet net(SmallConfig(NetKind::kClassifier));
  const ClassifierOutput out = net->forward(torch::rand({2, 3, 48, 64}) * 2 - 1);
  EXPECT_EQ(out.cams.sizes(), (std::vector<int64_t>{2, 4, 6, 8}));
  EXPECT_EQ(out.logits.sizes(), (std::vector<int64_t>{2, 4}));
  EXPECT_TRUE(torch::allclose(out.logits, out.cams.mean({2, 3}), 1e-5, 1e-7));
  out.logits.sum().backward();
  ExpectEveryParameterHasAGradient(*net);
}

TEST(SegmenterNet, OutputShapesAndGradients) {
  SegmenterNet net(SmallConfig(NetKind::kSegmenter));
  const SegmenterOutput out = net->forward(torch::rand({2, 3, 48, 64}) * 2 - 1);
  EXPECT_EQ(out.logits.sizes(), (std::vector<int64_t>{2, 4, 6, 8}));
  EXPECT_EQ(out.class_logits.sizes(), (std::vector<int64_t>{2, 4}));
  (out.logits.square().sum() + out.class_logits.sum()).backward();
  ExpectEveryParameterHasAGradient(*net);
}

TEST(SegmenterNet, DecoderGivesLogitsAtItsBlocksStride) {
  NetConfig config = SmallConfig(NetKind::kSegmenter);
  config.decoder_block = 3;  // stride 4
  config.decoder_channels = 8;
  SegmenterNet net(config);
  const SegmenterOutput out = net->forward(torch::rand({2, 3, 48, 64}) * 2 - 1);
  EXPECT_EQ(out.logits.sizes(), (std::vector<int64_t>{2, 4, 12, 16}));
  EXPECT_EQ(out.class_logits.sizes(), (std::vector<int64_t>{2, 4}));
  (out.logits.square().sum() + out.class_logits.sum()).backward();
  ExpectEveryParameterHasAGradient(*net);
  // Sizes that are not multiples of the stride: the head is upsampled to the block's grid.
  torch::NoGradGuard no_grad;
  EXPECT_EQ(net->forward(torch::rand({1, 3, 50, 70})).logits.sizes(),
            (std::vector<int64_t>{1, 4, 13, 18}));
}

TEST(MobileNetV2, TappedForwardReturnsTheBlockAndTheSameOutput) {
  BackboneOptions options;
  options.last_block = 6;
  options.output_stride = 8;
  MobileNetV2 backbone(options);
  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::rand({1, 3, 48, 64}) * 2 - 1;
  torch::Tensor tapped;
  const torch::Tensor y = backbone->forward(x, 3, &tapped);
  EXPECT_EQ(tapped.sizes(), (std::vector<int64_t>{1, BlockChannels(3), 12, 16}));
  EXPECT_TRUE(torch::allclose(y, backbone->forward(x), 1e-5, 1e-6));
}

TEST(ApplyConv, PointwiseGemmEqualsTheConvolution) {
  torch::manual_seed(5);
  torch::nn::Conv2d one(torch::nn::Conv2dOptions(6, 4, 1));
  torch::nn::Conv2d three(torch::nn::Conv2dOptions(6, 4, 3).padding(1));
  const torch::Tensor x = torch::rand({2, 6, 5, 7});
  for (const torch::Tensor& input : {x, x.contiguous(torch::MemoryFormat::ChannelsLast)}) {
    EXPECT_TRUE(torch::allclose(ApplyConv(*one, input), one->forward(x), 1e-5, 1e-6));
    EXPECT_TRUE(torch::allclose(ApplyConv(*three, input), three->forward(x), 1e-5, 1e-6));
  }
  // Gradients flow through the GEMM as through the convolution.
  ApplyConv(*one, x).square().sum().backward();
  const torch::Tensor gemm_grad = one->weight.grad().clone();
  one->weight.mutable_grad().zero_();
  one->forward(x).square().sum().backward();
  EXPECT_TRUE(torch::allclose(gemm_grad, one->weight.grad(), 1e-4, 1e-5));
}

TEST(SegmenterNet, ImagesAreIndependentInABatch) {
  SegmenterNet net(SmallConfig(NetKind::kSegmenter));
  torch::NoGradGuard no_grad;
  const torch::Tensor x = torch::rand({2, 3, 48, 64}) * 2 - 1;
  const SegmenterOutput both = net->forward(x);
  const SegmenterOutput second = net->forward(x.slice(0, 1, 2));
  EXPECT_TRUE(torch::allclose(both.logits.slice(0, 1, 2), second.logits, 1e-4, 1e-5));
  EXPECT_TRUE(torch::allclose(both.class_logits.slice(0, 1, 2), second.class_logits, 1e-4, 1e-5));
}

TEST(ImageToTensor, ColourGoesToRgbInMinusOneToOne) {
  const NetConfig config = SmallConfig(NetKind::kSegmenter);
  const cv::Mat blue(96, 128, CV_8UC3, cv::Scalar(255, 0, 0));  // BGR
  const torch::Tensor t = ImageToTensor(blue, config);
  EXPECT_EQ(t.sizes(), (std::vector<int64_t>{1, 3, 48, 64}));
  EXPECT_EQ(t.scalar_type(), torch::kFloat32);
  EXPECT_FLOAT_EQ(t[0][0].mean().item<float>(), -1.0f);  // R
  EXPECT_FLOAT_EQ(t[0][1].mean().item<float>(), -1.0f);  // G
  EXPECT_FLOAT_EQ(t[0][2].mean().item<float>(), 1.0f);   // B
}

TEST(ImageToTensor, GreyIsReplicatedAndGreyNetworksConvertColour) {
  NetConfig config = SmallConfig(NetKind::kSegmenter);
  cv::Mat grey(30, 40, CV_8UC1);  // enlarged
  cv::randu(grey, 0, 256);
  const torch::Tensor t = ImageToTensor(grey, config);
  EXPECT_EQ(t.sizes(), (std::vector<int64_t>{1, 3, 48, 64}));
  EXPECT_TRUE(torch::equal(t[0][0], t[0][1]));
  EXPECT_TRUE(torch::equal(t[0][0], t[0][2]));
  EXPECT_GE(t.min().item<float>(), -1.0f);
  EXPECT_LE(t.max().item<float>(), 1.0f);

  config.grey = true;
  const torch::Tensor c = ImageToTensor(cv::Mat(48, 64, CV_8UC3, cv::Scalar(255, 0, 0)), config);
  EXPECT_TRUE(torch::equal(c[0][0], c[0][2]));
  EXPECT_LT(c.max().item<float>(), 0.0f);  // blue is dark in grey
  EXPECT_THAT(ErrorOf([&] { ImageToTensor(cv::Mat(4, 4, CV_32FC1), config); }),
              HasSubstr("CV_8UC3"));
}

}  // namespace
}  // namespace moslam::net
