#include "moslam/net/model_file.h"

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
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

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

uint32_t Le32(const std::string& b, size_t at) {
  uint32_t v = 0;
  for (int i = 3; i >= 0; --i) v = v << 8 | static_cast<unsigned char>(b[at + i]);
  return v;
}

// The offset and size of the largest tensor record of a model file: a zip archive whose tensors
// are stored uncompressed, one record "<archive>/data/<n>" each, sizes in the central directory
// (the local headers defer them to data descriptors).
std::pair<size_t, size_t> LargestTensorRecord(const std::string& bytes) {
  std::pair<size_t, size_t> best{0, 0};
  for (size_t at = bytes.find("PK\x01\x02"); at != std::string::npos && at + 46 <= bytes.size();
       at = bytes.find("PK\x01\x02", at + 4)) {
    const size_t size = Le32(bytes, at + 20);
    const size_t name_length = Le32(bytes, at + 28) & 0xffffu;
    const std::string name = bytes.substr(at + 46, name_length);
    if (name.find("/data/") == std::string::npos || size <= best.second) continue;
    const size_t local = Le32(bytes, at + 42);
    const size_t data =
        local + 30 + (Le32(bytes, local + 26) & 0xffffu) + (Le32(bytes, local + 28) & 0xffffu);
    best = {data, size};
  }
  return best;
}

// Issue 31: libtorch does not check the zip records' CRCs, so a model file with flipped bytes in
// its weights loaded and ran; the format's checksum (version 2) refuses it.
TEST(ModelFile, FlippedBytesInTheWeightsAreRefused) {
  testing::TempDir dir;
  SegmenterNet net(SmallConfig(NetKind::kSegmenter));
  for (const bool half : {false, true}) {
    const std::string path = dir.path() + "/s.mnet";
    SaveSegmenter(path, net, half);
    EXPECT_NO_THROW(LoadSegmenter(path));
    std::string bytes = ReadBytes(path);
    const auto [offset, size] = LargestTensorRecord(bytes);
    ASSERT_GT(size, 64u) << "no tensor record found";
    for (size_t i = 0; i < 16; ++i) bytes[offset + size / 2 + 3 * i] ^= 0x5a;
    const std::string damaged = dir.Write("damaged.mnet", bytes);
    EXPECT_THAT(ErrorOf([&] { LoadSegmenter(damaged); }),
                ::testing::AllOf(HasSubstr(damaged), HasSubstr("damaged"), HasSubstr("CRC-32")))
        << (half ? "float16" : "float32");
  }
}

// A model file as format version `version` lays it out without a checksum (version 1 wrote
// exactly this).
void SaveWithoutChecksum(const std::string& path, SegmenterNet& net, int64_t version) {
  c10::Dict<std::string, at::Tensor> weights;
  for (const auto& p : net->named_parameters()) weights.insert(p.key(), p.value().detach().clone());
  for (const auto& b : net->named_buffers()) weights.insert(b.key(), b.value().detach().clone());
  torch::serialize::OutputArchive archive;
  archive.write("format", c10::IValue(std::string("moslam-net")));
  archive.write("version", c10::IValue(version));
  archive.write("kind", c10::IValue(std::string("segmenter")));
  archive.write("config", c10::IValue(ToJson(net->config()).dump()));
  archive.write("weights", c10::IValue(weights));
  archive.save_to(path);
}

TEST(ModelFile, VersionOneFilesWithoutChecksumStillLoad) {
  testing::TempDir dir;
  SegmenterNet net(SmallConfig(NetKind::kSegmenter));
  net->eval();
  const std::string v1 = dir.path() + "/v1.mnet";
  SaveWithoutChecksum(v1, net, 1);
  SegmenterNet loaded = LoadSegmenter(v1);
  loaded->eval();
  torch::NoGradGuard no_grad;
  EXPECT_TRUE(torch::equal(loaded->forward(Input()).logits, net->forward(Input()).logits));
  // A version 2 file must carry its checksum; a later version is not read at all.
  const std::string v2 = dir.path() + "/v2.mnet";
  SaveWithoutChecksum(v2, net, 2);
  EXPECT_THAT(ErrorOf([&] { LoadSegmenter(v2); }),
              ::testing::AllOf(HasSubstr(v2), HasSubstr("checksum")));
  const std::string v9 = dir.path() + "/v9.mnet";
  SaveWithoutChecksum(v9, net, 9);
  EXPECT_THAT(ErrorOf([&] { LoadSegmenter(v9); }),
              ::testing::AllOf(HasSubstr(v9), HasSubstr("version 9")));
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
