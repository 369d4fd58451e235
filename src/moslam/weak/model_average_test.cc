// Weight averaging of segmenters on small random networks (no data needed).
#include "moslam/weak/model_average.h"

#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "moslam/net/model_file.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::weak {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

net::NetConfig SmallConfig() {
  net::NetConfig config;
  config.kind = net::NetKind::kSegmenter;
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

// A randomly initialized segmenter saved in float32 (seeded, so two seeds differ everywhere).
std::string SavedNet(const testing::TempDir& dir, const std::string& name, uint64_t seed,
                     const net::NetConfig& config = SmallConfig()) {
  torch::manual_seed(seed);
  net::SegmenterNet net(config);
  const std::string path = dir.path() + "/" + name;
  net::SaveSegmenter(path, net);
  return path;
}

TEST(ModelAverage, EveryTensorIsTheElementWiseMean) {
  testing::TempDir dir;
  const std::string a = SavedNet(dir, "a.mnet", 1), b = SavedNet(dir, "b.mnet", 2),
                    c = SavedNet(dir, "c.mnet", 3);
  net::SegmenterNet na = net::LoadSegmenter(a), nb = net::LoadSegmenter(b),
                    nc = net::LoadSegmenter(c);
  net::SegmenterNet mean = AverageSegmenters({a, b, c});
  const auto pa = na->named_parameters(), pb = nb->named_parameters(), pc = nc->named_parameters();
  int differing = 0;
  for (const auto& item : mean->named_parameters()) {
    const torch::Tensor expected = (pa[item.key()] + pb[item.key()] + pc[item.key()]) / 3.0;
    EXPECT_TRUE(torch::allclose(item.value(), expected, 1e-6, 1e-7)) << item.key();
    if (!torch::equal(pa[item.key()], pb[item.key()])) ++differing;
  }
  // Every weight is random here (biases start at zero): the comparison above is not between
  // equal inputs for 24 of the 48 tensors.
  EXPECT_GE(differing, 20);
  EXPECT_EQ(net::ToJson(mean->config()), net::ToJson(SmallConfig()));
}

TEST(ModelAverage, TheAverageOfANetworkWithItselfPredictsTheSame) {
  testing::TempDir dir;
  const std::string a = SavedNet(dir, "a.mnet", 5);
  std::filesystem::copy_file(a, dir.path() + "/same.mnet");
  net::SegmenterNet original = net::LoadSegmenter(a);
  net::SegmenterNet mean = AverageSegmenters({a, dir.path() + "/same.mnet"});
  original->eval();
  mean->eval();
  torch::NoGradGuard no_grad;
  torch::manual_seed(9);
  const torch::Tensor input = torch::rand({1, 3, 32, 48}) * 2 - 1;
  EXPECT_TRUE(
      torch::allclose(mean->forward(input).logits, original->forward(input).logits, 1e-5, 1e-6));
}

TEST(ModelAverage, DifferentNetworksAndTooFewModelsAreInputErrors) {
  testing::TempDir dir;
  const std::string a = SavedNet(dir, "a.mnet", 1);
  net::NetConfig wider = SmallConfig();
  wider.head_channels = 16;
  const std::string w = SavedNet(dir, "wider.mnet", 1, wider);
  EXPECT_THAT(ErrorOf([&] { AverageSegmenters({a, w}); }), HasSubstr("wider.mnet"));
  EXPECT_THAT(ErrorOf([&] { AverageSegmenters({a}); }), HasSubstr("at least two"));
  AverageOptions options;
  options.models = {a};
  options.out = dir.path() + "/out";
  EXPECT_THROW(options.Check(), InputError);
}

TEST(ModelAverage, FilesAreWrittenWithAReport) {
  testing::TempDir dir;
  AverageOptions options;
  options.models = {SavedNet(dir, "a.mnet", 1), SavedNet(dir, "b.mnet", 2)};
  options.out = dir.path() + "/soup";
  AverageSegmenterFiles(options);
  net::SegmenterNet loaded = net::LoadSegmenter(options.out + "/model.mnet");
  EXPECT_EQ(net::ToJson(loaded->config()), net::ToJson(SmallConfig()));
  std::ifstream file(options.out + "/report.json");
  const nlohmann::json report = nlohmann::json::parse(file);
  EXPECT_EQ(report["models"].get<std::vector<std::string>>(), options.models);
  EXPECT_TRUE(report["half"].get<bool>());
}

}  // namespace
}  // namespace moslam::weak
