#include "moslam/net/model_file.h"

#include <filesystem>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::net {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

NetConfig SmallConfig(NetKind kind) {
  NetConfig config;
  config.kind = kind;
  config.classes = {"road", "car", "person"};
  config.movable = {"car", "person"};
  config.backbone.last_block = 6;
  config.backbone.output_stride = 8;
  config.backbone.frozen_blocks = 2;
  config.head_channels = 8;
  config.head_dilations = {2};
  config.input_width = 48;
  config.input_height = 32;
  return config;
}

torch::Tensor Input() {
  torch::manual_seed(11);
  return torch::rand({2, 3, 32, 48}) * 2 - 1;
}

double MaxRelativeDifference(const torch::Tensor& a, const torch::Tensor& b) {
  return (a - b).abs().max().item<double>() / b.abs().max().item<double>();
}

TEST(ModelFile, ClassifierRoundTrip) {
  testing::TempDir dir;
  ClassifierNet net(SmallConfig(NetKind::kClassifier));
  const std::string path = dir.path() + "/c.mnet", half_path = dir.path() + "/h.mnet";
  SaveClassifier(path, net);
  SaveClassifier(half_path, net, /*half=*/true);
  EXPECT_LT(std::filesystem::file_size(half_path), std::filesystem::file_size(path));
  ClassifierNet loaded = LoadClassifier(path), half = LoadClassifier(half_path);
  EXPECT_EQ(ToJson(loaded->config()), ToJson(net->config()));
  torch::NoGradGuard no_grad;
  const ClassifierOutput expected = net->forward(Input());
  // The round trip is exact in the weights; the outputs of two forward passes need not be
  // bit-identical, because OpenBLAS's AVX2 kernels with two threads split the sums differently
  // for different buffer addresses (seen on an AMD EPYC with the Zen kernels; the generic
  // Prescott kernels, or one thread, give equal outputs).
  const auto saved = net->named_parameters(), read = loaded->named_parameters();
  ASSERT_EQ(saved.size(), read.size());
  for (const auto& item : saved) {
    EXPECT_TRUE(torch::equal(item.value(), read[item.key()])) << item.key();
  }
  EXPECT_LT(MaxRelativeDifference(loaded->forward(Input()).cams, expected.cams), 1e-6);
  const ClassifierOutput h = half->forward(Input());
  EXPECT_EQ(h.cams.scalar_type(), torch::kFloat32);
  EXPECT_LT(MaxRelativeDifference(h.cams, expected.cams), 1e-2);
  // Freezing is part of the config and survives loading.
  EXPECT_FALSE(loaded->backbone()->parameters().front().requires_grad());
  EXPECT_TRUE(loaded->backbone()->parameters().back().requires_grad());
}

TEST(ModelFile, SegmenterRoundTrip) {
  testing::TempDir dir;
  SegmenterNet net(SmallConfig(NetKind::kSegmenter));
  const std::string path = dir.path() + "/s.mnet", half_path = dir.path() + "/h.mnet";
  SaveSegmenter(path, net);
  SaveSegmenter(half_path, net, /*half=*/true);
  SegmenterNet loaded = LoadSegmenter(path), half = LoadSegmenter(half_path);
  EXPECT_EQ(ReadNetConfig(path).kind, NetKind::kSegmenter);
  torch::NoGradGuard no_grad;
  const SegmenterOutput expected = net->forward(Input());
  const SegmenterOutput same = loaded->forward(Input());
  EXPECT_TRUE(torch::equal(same.logits, expected.logits));
  EXPECT_TRUE(torch::equal(same.class_logits, expected.class_logits));
  const SegmenterOutput h = half->forward(Input());
  EXPECT_LT(MaxRelativeDifference(h.logits, expected.logits), 1e-2);
  EXPECT_LT(MaxRelativeDifference(h.class_logits, expected.class_logits), 1e-2);
}

TEST(ModelFile, SegmenterWithDecoderRoundTrips) {
  testing::TempDir dir;
  NetConfig config = SmallConfig(NetKind::kSegmenter);
  config.decoder_block = 3;
  config.decoder_channels = 6;
  SegmenterNet net(config);
  const std::string path = dir.path() + "/d.mnet";
  SaveSegmenter(path, net);
  SegmenterNet loaded = LoadSegmenter(path);
  EXPECT_EQ(loaded->config().decoder_block, 3);
  EXPECT_EQ(loaded->config().decoder_channels, 6);
  torch::NoGradGuard no_grad;
  const torch::Tensor expected = net->forward(Input()).logits;
  EXPECT_EQ(expected.size(2), 8);  // stride 4 of 32 rows
  EXPECT_TRUE(torch::equal(loaded->forward(Input()).logits, expected));
}

TEST(ModelFile, WrongKindMissingFileAndGarbageAreInputErrors) {
  testing::TempDir dir;
  ClassifierNet classifier(SmallConfig(NetKind::kClassifier));
  const std::string path = dir.path() + "/c.mnet";
  SaveClassifier(path, classifier);
  EXPECT_THAT(ErrorOf([&] { LoadSegmenter(path); }), HasSubstr("not a segmenter"));
  EXPECT_THAT(ErrorOf([&] { LoadClassifier(dir.path() + "/none.mnet"); }), HasSubstr("none.mnet"));
  const std::string text = dir.Write("text.mnet", "not a model");
  EXPECT_THAT(ErrorOf([&] { LoadClassifier(text); }), HasSubstr("text.mnet"));
  // No temporary file is left behind.
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.path())) {
    EXPECT_EQ(entry.path().extension(), ".mnet") << entry.path();
    ++files;
  }
  EXPECT_EQ(files, 2);
}

// A few Adam steps on a fixed regression target.
void Train(ClassifierNet& net, torch::optim::Adam& adam, int steps) {
  const torch::Tensor x = Input();
  const torch::Tensor target = torch::tensor({{1.0f, 0.0f, 1.0f}, {0.0f, 1.0f, 0.0f}});
  for (int i = 0; i < steps; ++i) {
    adam.zero_grad();
    torch::binary_cross_entropy_with_logits(net->forward(x).logits, target).backward();
    adam.step();
  }
}

TEST(ModelFile, CheckpointResumesTrainingIdentically) {
  testing::TempDir dir;
  const NetConfig config = SmallConfig(NetKind::kClassifier);
  torch::manual_seed(1);
  ClassifierNet net(config);
  torch::optim::Adam adam(net->parameters(), torch::optim::AdamOptions(1e-2));
  Train(net, adam, 3);
  const std::string path = dir.path() + "/checkpoint.mnet";
  const nlohmann::json state = {{"epoch", 3}, {"loss", {0.7, 0.5, 0.4}}};
  SaveCheckpoint(path, *net, config, adam, state);
  Train(net, adam, 2);

  torch::manual_seed(2);  // other initial weights: everything must come from the checkpoint
  ClassifierNet resumed(ReadNetConfig(path));
  torch::optim::Adam resumed_adam(resumed->parameters(), torch::optim::AdamOptions(1e-2));
  EXPECT_EQ(LoadCheckpoint(path, *resumed, resumed_adam), state);
  Train(resumed, resumed_adam, 2);
  auto expected = net->named_parameters();
  for (const auto& p : resumed->named_parameters()) {
    EXPECT_TRUE(torch::allclose(p.value(), expected[p.key()], 1e-5, 1e-7)) << p.key();
  }
  // A checkpoint is also a model file.
  EXPECT_EQ(LoadClassifier(path)->config().classes, config.classes);
}

TEST(ModelFile, AModelFileIsNotACheckpoint) {
  testing::TempDir dir;
  ClassifierNet net(SmallConfig(NetKind::kClassifier));
  const std::string path = dir.path() + "/c.mnet";
  SaveClassifier(path, net);
  torch::optim::Adam adam(net->parameters());
  EXPECT_THAT(ErrorOf([&] { LoadCheckpoint(path, *net, adam); }), HasSubstr("checkpoint"));
}

}  // namespace
}  // namespace moslam::net
