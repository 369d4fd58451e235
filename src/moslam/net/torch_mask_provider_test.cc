// The libtorch mask provider on an untrained tiny segmenter whose last layers are set by hand, so
// that one class wins everywhere: mask polarity, shapes, card completion and class mapping.
#include "moslam/net/torch_mask_provider.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <torch/torch.h>
#include <opencv2/core.hpp>

#include "moslam/net/model_file.h"
#include "moslam/net/networks.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"

namespace moslam::net {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::AllOf;
using ::testing::HasSubstr;

NetConfig TinyConfig() {
  NetConfig config;
  config.kind = NetKind::kSegmenter;
  config.classes = {"road", "car", "tree"};
  config.movable = {"car"};
  config.backbone.last_block = 4;  // stride 8, 32 channels: the smallest backbone allowed
  config.backbone.output_stride = 8;
  config.head_channels = 8;
  config.input_width = 64;
  config.input_height = 48;
  return config;
}

// A segmenter whose class outputs (pixel and image level) are `winner` everywhere: every layer
// with one output per class gets zero weights and a bias favouring `winner` (the other layers
// have 8 or more outputs, so none is mistaken for a class layer).
std::string SaveForcedSegmenter(const testing::TempDir& dir, int winner,
                                const std::string& name = "tiny.mnet") {
  torch::manual_seed(1);
  SegmenterNet net(TinyConfig());
  const int64_t classes = 3;
  torch::NoGradGuard no_grad;
  int class_layers = 0;
  for (auto& p : net->named_parameters()) {
    torch::Tensor t = p.value();
    if (t.dim() == 0 || t.size(0) != classes) continue;
    t.zero_();
    if (t.dim() == 1) {
      t[winner] = 20.0f;
      ++class_layers;
    }
  }
  EXPECT_GE(class_layers, 1);
  const std::string path = dir.path() + "/" + name;
  SaveSegmenter(path, net);
  return path;
}

cv::Mat RandomImage(int rows, int cols, int type) {
  cv::Mat image(rows, cols, type);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(255));
  return image;
}

semantic::RefineOptions Refine(int working_side, float suppress_below = 0.0f) {
  semantic::RefineOptions refine;
  refine.working_side = working_side;
  refine.suppress_below = suppress_below;
  return refine;
}

TEST(TorchMaskProvider, MovableClassEverywhereGivesAFullMask) {
  testing::TempDir dir;
  SaveForcedSegmenter(dir, 1);  // car
  const semantic::ModelCard card =
      LoadAnyModelCard(dir.Write("card.yaml", "%YAML:1.0\ntype: torch\nmodel: tiny.mnet\n"));
  EXPECT_EQ(card.classes, TinyConfig().classes);
  EXPECT_EQ(card.movable, std::vector<std::string>{"car"});
  EXPECT_EQ(card.input_width, 64);
  EXPECT_EQ(card.input_height, 48);
  const auto provider = MakeAnyMaskProvider(card, Refine(40));
  EXPECT_EQ(provider->class_names(), TinyConfig().classes);
  EXPECT_EQ(provider->movable(), (std::vector<bool>{false, true, false}));
  EXPECT_THAT(provider->Describe(), AllOf(HasSubstr("torch card"), HasSubstr("movable: car")));

  const semantic::MaskResult r = provider->Segment({RandomImage(80, 100, CV_8UC3), {}});
  ASSERT_EQ(r.mask.type(), CV_8UC1);
  ASSERT_EQ(r.mask.size(), cv::Size(100, 80));
  EXPECT_EQ(cv::countNonZero(r.mask == 255), 100 * 80);
  ASSERT_EQ(r.probabilities.dims, 3);
  EXPECT_EQ(r.probabilities.size[0], 3);
  EXPECT_EQ(r.probabilities.size[1], 32);  // working size 40 x 32
  EXPECT_EQ(r.probabilities.size[2], 40);
  EXPECT_EQ(r.labels.size(), cv::Size(40, 32));
  EXPECT_EQ(cv::countNonZero(r.labels == 1), 40 * 32);
  ASSERT_EQ(r.image_scores.size(), 3u);
  EXPECT_GT(r.image_scores[1], 0.99f);  // the network's image-level score, sigmoid(20)
  EXPECT_GT(r.network_ms, 0.0);
}

TEST(TorchMaskProvider, StaticClassEverywhereGivesAnEmptyMaskForEveryImageType) {
  testing::TempDir dir;
  const std::string model = SaveForcedSegmenter(dir, 0);  // road
  TorchMaskProvider provider(TorchModelCard(model), Refine(0));
  for (int type : {CV_8UC1, CV_8UC3, CV_8UC4}) {
    const semantic::MaskResult r = provider.Segment({RandomImage(30, 50, type), {}});
    ASSERT_EQ(r.mask.size(), cv::Size(50, 30));
    EXPECT_EQ(cv::countNonZero(r.mask), 0) << "type " << type;
    EXPECT_EQ(r.labels.size(), cv::Size(50, 30));  // working side 0: the image's size
  }
  EXPECT_EQ(provider.card().name, "tiny");
  EXPECT_THROW(provider.Segment({cv::Mat(10, 10, CV_32F, cv::Scalar(0)), {}}), InputError);
}

TEST(TorchMaskProvider, CardMovableClassesReplaceTheModels) {
  testing::TempDir dir;
  SaveForcedSegmenter(dir, 0);  // road, not movable in the model
  semantic::ModelCard card = LoadAnyModelCard(
      dir.Write("card.yaml", "%YAML:1.0\ntype: torch\nmodel: tiny.mnet\nmovable: [road]\n"));
  EXPECT_EQ(card.MovableFlags(), (std::vector<bool>{true, false, false}));
  TorchMaskProvider provider(card, Refine(32));
  EXPECT_EQ(cv::countNonZero(provider.Segment({RandomImage(24, 32, CV_8UC3), {}}).mask), 24 * 32);
  // --movable on a completed card, as `moslam segment` and `moslam run` do it.
  semantic::SetMovable({"tree"}, &card);
  TorchMaskProvider tree(card, Refine(32));
  EXPECT_EQ(cv::countNonZero(tree.Segment({RandomImage(24, 32, CV_8UC3), {}}).mask), 0);
}

TEST(TorchMaskProvider, CardInputSizeIsWhatTheNetworkRunsAt) {
  testing::TempDir dir;
  SaveForcedSegmenter(dir, 1);  // car, a 64x48 model
  const semantic::ModelCard card = LoadAnyModelCard(dir.Write(
      "big.yaml", "%YAML:1.0\ntype: torch\nmodel: tiny.mnet\ninput_width: 96\ninput_height: 72\n"));
  EXPECT_EQ(card.input_width, 96);
  EXPECT_EQ(card.input_height, 72);
  TorchMaskProvider provider(card, Refine(32));
  EXPECT_THAT(provider.Describe(), HasSubstr("96x72"));
  EXPECT_EQ(cv::countNonZero(provider.Segment({RandomImage(24, 32, CV_8UC3), {}}).mask), 24 * 32);
}

TEST(TorchMaskProvider, SuppressionReadsTheNetworksClassScores) {
  testing::TempDir dir;
  const std::string model = SaveForcedSegmenter(dir, 1);
  // Image-level scores: car sigmoid(20) ~ 1, road and tree sigmoid(0) = 0.5.
  TorchMaskProvider provider(TorchModelCard(model), Refine(32, 0.6f));
  const semantic::MaskResult r = provider.Segment({RandomImage(24, 32, CV_8UC3), {}});
  EXPECT_EQ(r.suppressed, (std::vector<int>{0, 2}));
  EXPECT_NEAR(r.image_scores[0], 0.5f, 1e-4f);
  EXPECT_EQ(cv::countNonZero(r.mask), 24 * 32);
}

TEST(TorchMaskProvider, CardsThatDisagreeWithTheModelAreInputErrors) {
  testing::TempDir dir;
  SaveForcedSegmenter(dir, 1);
  auto load = [&](const std::string& extra) {
    return ErrorOf([&] {
      LoadAnyModelCard(
          dir.Write("bad.yaml", "%YAML:1.0\ntype: torch\nmodel: tiny.mnet\n" + extra + "\n"));
    });
  };
  // The same classes in the same order are accepted.
  EXPECT_EQ(LoadAnyModelCard(dir.Write("ok.yaml",
                                       "%YAML:1.0\ntype: torch\nmodel: tiny.mnet\n"
                                       "classes: [road, car, tree]\ninput_width: 64\n"
                                       "input_height: 48\n"))
                .classes.size(),
            3u);
  EXPECT_THAT(load("classes: [car, road, tree]"), AllOf(HasSubstr("classes"), HasSubstr("bad")));
  EXPECT_THAT(load("input_width: 16\ninput_height: 48"), HasSubstr("input_width"));
  EXPECT_THAT(load("movable: [bus]"), HasSubstr("'bus'"));
  EXPECT_THAT(load("background: road"), HasSubstr("background"));
  EXPECT_THAT(load("scale: 0.5"), HasSubstr("scale"));
  semantic::ModelCard onnx = TorchModelCard(dir.path() + "/tiny.mnet");
  onnx.kind = semantic::ModelKind::kSegmentation;
  EXPECT_THAT(ErrorOf([&] { TorchMaskProvider provider(onnx, Refine(32)); }),
              HasSubstr("torch card"));
}

}  // namespace
}  // namespace moslam::net
