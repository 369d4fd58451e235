#include "moslam/semantic/model_card.h"

#include <filesystem>

#include <fmt/format.h>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::semantic {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::AllOf;
using ::testing::HasSubstr;

constexpr const char* kCard =
    "%YAML:1.0\n"
    "type: segmentation\n"
    "model: net.onnx\n"
    "input_width: 64\n"
    "input_height: 48\n"
    "mean: [127.5, 127.5, 127.5]\n"
    "scale: 0.5\n"
    "rgb: false\n"
    "classes: [background, person, car, tree]\n"
    "movable: [person, car]\n"
    "background: background\n"
    "refine:\n"
    "  working_side: 100\n"
    "  suppress_below: 0.3\n"
    "  movable_bias: -0.75\n"
    "crf:\n"
    "  iterations: 3\n";

TEST(ModelCard, ReadsEveryKeyAndResolvesTheModelBesideTheCard) {
  testing::TempDir dir;
  dir.Write("net.onnx", "not a network");
  const ModelCard card = LoadModelCard(dir.Write("card.yaml", kCard), "/nonexistent");
  EXPECT_EQ(card.name, "card");
  EXPECT_EQ(card.kind, ModelKind::kSegmentation);
  EXPECT_EQ(std::filesystem::path(card.model).filename(), "net.onnx");
  EXPECT_EQ(card.input_width, 64);
  EXPECT_EQ(card.input_height, 48);
  EXPECT_DOUBLE_EQ(card.scale, 0.5);
  EXPECT_FALSE(card.rgb);
  EXPECT_EQ(card.MovableFlags(), (std::vector<bool>{false, true, true, false}));
  EXPECT_EQ(card.BackgroundIndex(), 0);
  EXPECT_EQ(card.refine.working_side, 100);
  EXPECT_FLOAT_EQ(card.refine.suppress_below, 0.3f);
  EXPECT_FLOAT_EQ(card.refine.movable_bias, -0.75f);
  EXPECT_EQ(card.refine.crf_options.iterations, 3);
}

TEST(ModelCard, ModelFallsBackToTheSharedRoot) {
  testing::TempDir cards;
  testing::TempDir shared;
  std::filesystem::create_directories(shared.path() + "/models");
  shared.Write("models/net.onnx", "x");
  std::string text = kCard;
  text.replace(text.find("net.onnx"), 8, "models/net.onnx");
  const ModelCard card = LoadModelCard(cards.Write("card.yaml", text), shared.path());
  EXPECT_EQ(card.model, shared.path() + "/models/net.onnx");
}

TEST(ModelCard, ErrorsNameTheKeyAndTheCard) {
  testing::TempDir dir;
  dir.Write("net.onnx", "x");
  auto load = [&](const std::string& text) {
    return ErrorOf([&] { LoadModelCard(dir.Write("bad.yaml", text), "/nonexistent"); });
  };
  EXPECT_THAT(load(std::string(kCard) + "colour_order: rgb\n"),
              AllOf(HasSubstr("colour_order"), HasSubstr("bad.yaml")));
  std::string unknown_movable = kCard;
  unknown_movable.replace(unknown_movable.find("[person, car]"), 13, "[person, bus]");
  EXPECT_THAT(load(unknown_movable), AllOf(HasSubstr("movable"), HasSubstr("'bus'")));
  std::string missing_model = kCard;
  missing_model.replace(missing_model.find("net.onnx"), 8, "gone.onnx");
  EXPECT_THAT(load(missing_model), AllOf(HasSubstr("model"), HasSubstr("gone.onnx")));
  std::string bad_type = kCard;
  bad_type.replace(bad_type.find("segmentation"), 12, "classifier");
  EXPECT_THAT(load(bad_type), HasSubstr("type"));
  EXPECT_THAT(load(std::string(kCard) + "nms: 2\n"), HasSubstr("nms"));
  EXPECT_THAT(load(std::string(kCard) + "threads: 0\n"), HasSubstr("threads"));
}

TEST(ModelCard, SetMovableReplacesTheMovableClasses) {
  testing::TempDir dir;
  dir.Write("net.onnx", "x");
  ModelCard card = LoadModelCard(dir.Write("card.yaml", kCard), "/nonexistent");
  SetMovable({"car"}, &card);
  EXPECT_EQ(card.MovableFlags(), (std::vector<bool>{false, false, true, false}));
  EXPECT_THAT(ErrorOf([&] { SetMovable({"boat"}, &card); }),
              AllOf(HasSubstr("--movable"), HasSubstr("boat")));
}

TEST(ModelCard, TorchCardsTakeSizeAndClassesFromTheModelFile) {
  testing::TempDir dir;
  dir.Write("net.mnet", "x");
  const ModelCard card =
      LoadModelCard(dir.Write("card.yaml", "%YAML:1.0\ntype: torch\nmodel: net.mnet\n"), "/none");
  EXPECT_EQ(card.kind, ModelKind::kTorch);
  EXPECT_STREQ(ToString(card.kind), "torch");
  EXPECT_EQ(card.input_width, 0);
  EXPECT_TRUE(card.classes.empty());
  EXPECT_TRUE(card.movable.empty());
  EXPECT_DOUBLE_EQ(card.scale, 1.0 / 127.5);  // what the networks take: RGB in [-1, 1]
  EXPECT_EQ(card.threads, 2);
  EXPECT_EQ(
      LoadModelCard(dir.Write("one.yaml", "%YAML:1.0\ntype: torch\nmodel: net.mnet\nthreads: 1\n"),
                    "/none")
          .threads,
      1);
  // Given classes are still checked as in any card.
  EXPECT_THAT(ErrorOf([&] {
                LoadModelCard(dir.Write("bad.yaml",
                                        "%YAML:1.0\ntype: torch\nmodel: net.mnet\n"
                                        "classes: [a, b]\nmovable: [c]\n"),
                              "/none");
              }),
              AllOf(HasSubstr("movable"), HasSubstr("'c'")));
  // An ONNX card still needs its input size.
  EXPECT_THAT(ErrorOf([&] {
                LoadModelCard(dir.Write("onnx.yaml",
                                        "%YAML:1.0\ntype: segmentation\nmodel: net.mnet\n"
                                        "classes: [a, b]\nmovable: [b]\n"),
                              "/none");
              }),
              HasSubstr("input_width"));
}

// Issue 31: sizes that failed inside OpenCV dnn (1x1, 7x5: "Inconsistent shape" in a concat
// layer) or ran for minutes a frame (8000x6000) are refused with the keys and the card named.
TEST(ModelCard, InputSizesOutsideTheLimitsAreRefused) {
  testing::TempDir dir;
  dir.Write("net.onnx", "x");
  dir.Write("net.cfg", "x");
  dir.Write("net.mnet", "x");
  const auto card = [&](const std::string& head, int w, int h) {
    return dir.Write("card.yaml", fmt::format("%YAML:1.0\n{}input_width: {}\ninput_height: {}\n"
                                              "classes: [a, b]\nmovable: [b]\n",
                                              head, w, h));
  };
  for (const std::string head :
       {"type: segmentation\nmodel: net.onnx\n",
        "type: detector\nmodel: net.onnx\nconfig: net.cfg\n", "type: torch\nmodel: net.mnet\n"}) {
    for (const auto& [w, h] : std::vector<std::pair<int, int>>{{1, 1}, {7, 5}, {8000, 6000}}) {
      const std::string path = card(head, w, h);
      EXPECT_THAT(ErrorOf([&] { LoadModelCard(path, "/none"); }),
                  AllOf(HasSubstr(path), HasSubstr("input_width, input_height"),
                        HasSubstr(fmt::format("{}x{}", w, h))))
          << head << w << "x" << h;
    }
  }
  // A Darknet detector needs multiples of 32; other networks take any size in the range.
  const std::string darknet = card("type: detector\nmodel: net.onnx\nconfig: net.cfg\n", 100, 96);
  EXPECT_THAT(ErrorOf([&] { LoadModelCard(darknet, "/none"); }),
              AllOf(HasSubstr(darknet), HasSubstr("multiples of 32")));
  EXPECT_NO_THROW(LoadModelCard(card("type: segmentation\nmodel: net.onnx\n", 513, 100), "/none"));
}

TEST(ModelCard, AnUnreadableCardIsNamed) {
  testing::TempDir dir;
  const std::string list = dir.Write("list.yaml", "%YAML:1.0\n- type: torch\n- model: x\n");
  EXPECT_THAT(ErrorOf([&] { LoadModelCard(list, "/none"); }),
              AllOf(HasSubstr(list), HasSubstr("top level")));
  const std::string broken = dir.Write("broken.yaml", "%YAML:1.0\ntype: [torch\nmodel: {x\n");
  EXPECT_THAT(ErrorOf([&] { LoadModelCard(broken, "/none"); }), HasSubstr(broken));
  EXPECT_THAT(ErrorOf([&] { LoadModelCard(dir.path(), "/none"); }),
              AllOf(HasSubstr(dir.path()), HasSubstr("is a directory")));
}

// The cards shipped in configs/models/ parse and name models that exist in the shared folder.
TEST(ModelCard, ShippedCardsLoad) {
  MOSLAM_SHARED_OR_SKIP(models, "models");
  const std::string root = ::moslam::testing::SharedRoot();
  const ModelCard deeplab = LoadModelCard("configs/models/deeplabv3_mnv2_voc.yaml", root);
  EXPECT_EQ(deeplab.classes.size(), 21u);
  EXPECT_EQ(deeplab.MovableFlags()[15], true);  // VOC 15 = person
  const ModelCard yolo = LoadModelCard("configs/models/yolo_fastest_coco.yaml", root);
  EXPECT_EQ(yolo.kind, ModelKind::kDetector);
  EXPECT_EQ(yolo.classes.size(), 80u);
  EXPECT_FALSE(yolo.config.empty());
}

}  // namespace
}  // namespace moslam::semantic
