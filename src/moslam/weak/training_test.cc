// The training loops end to end on a toy task: red squares and blue discs on noise. A classifier
// (from the ImageNet backbone) must learn which shapes an image contains, its class activation maps
// must peak on the shapes, and cues and a segmenter must come out of the same command sequence.
#include <filesystem>
#include <fstream>
#include <random>

#include <fmt/format.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/net/model_file.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/util/error.h"
#include "moslam/weak/training.h"
#include "moslam/weak/training_loop.h"

namespace moslam::weak {
namespace {

namespace fs = std::filesystem;

struct ToyImage {
  bool square = false, disc = false;
  cv::Rect square_box, disc_box;
};

// Writes `count` 64x48 images, their image list, classes file and (for evaluating cues only)
// label images: 0 background, 1 square, 2 disc.
std::vector<ToyImage> WriteToyData(const std::string& folder, int count) {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> noise(60, 160), x(4, 36), y(4, 24);
  fs::create_directories(folder + "/images");
  fs::create_directories(folder + "/labels");
  std::ofstream list(folder + "/list.txt");
  std::ofstream(folder + "/classes.txt") << "0 background 0\n1 square 1\n2 disc 0\n";
  std::vector<ToyImage> toys;
  for (int i = 0; i < count; ++i) {
    cv::Mat image(48, 64, CV_8UC3), labels(48, 64, CV_8U, cv::Scalar(0));
    for (int p = 0; p < image.rows * image.cols; ++p) {
      image.at<cv::Vec3b>(p / 64, p % 64) = cv::Vec3b(noise(rng), noise(rng), noise(rng));
    }
    ToyImage toy;
    toy.square = (i % 4 == 0 || i % 4 == 1);
    toy.disc = (i % 4 == 1 || i % 4 == 2);
    std::string classes;
    if (toy.square) {
      toy.square_box = cv::Rect(x(rng), y(rng), 16, 16);
      cv::rectangle(image, toy.square_box, cv::Scalar(20, 20, 230), cv::FILLED);
      labels(toy.square_box).setTo(1);
      classes += " square";
    }
    if (toy.disc) {
      toy.disc_box = cv::Rect(x(rng), y(rng), 16, 16);
      const cv::Point centre(toy.disc_box.x + 8, toy.disc_box.y + 8);
      cv::circle(image, centre, 8, cv::Scalar(230, 40, 20), cv::FILLED);
      cv::circle(labels, centre, 8, cv::Scalar(2), cv::FILLED);
      classes += " disc";
    }
    const std::string name = fmt::format("{:03d}.png", i);
    cv::imwrite(folder + "/images/" + name, image);
    cv::imwrite(folder + "/labels/" + name, labels);
    list << "images/" << name << classes << "\n";
    toys.push_back(toy);
  }
  return toys;
}

CommonTrainOptions ToyOptions(const std::string& folder, const std::string& out) {
  CommonTrainOptions o;
  o.data.list = folder + "/list.txt";
  o.data.classes = folder + "/classes.txt";
  o.out = out;
  o.epochs = 12;
  o.batch_size = 8;
  o.learning_rate = 3e-3;
  o.threads = 1;
  o.preview_images = 2;
  o.augment.output_width = 64;
  o.augment.output_height = 48;
  o.augment.crop_probability = 0.0;
  return o;
}

// The backbone starts from the ImageNet weights, as in real training: without BatchNorm, a
// randomly initialized MobileNetV2 does not train at all in this budget (its output stays flat).
ClassifierTrainOptions ToyClassifier(const std::string& folder, const std::string& out,
                                     const std::string& weights) {
  ClassifierTrainOptions o;
  o.common = ToyOptions(folder, out);
  o.imagenet_weights = weights;
  o.net.backbone.last_block = 6;  // 32 channels at stride 8
  o.net.backbone.output_stride = 8;
  return o;
}

constexpr char kWeights[] = "models/mobilenet_v2_imagenet/mobilenet_v2_imagenet.torchscript.pt";

class TrainingTest : public ::testing::Test {
 protected:
  testing::TempDir dir_;
  std::string data_ = dir_.path() + "/data";
  std::vector<ToyImage> toys_ = WriteToyData(data_, 32);
};

TEST_F(TrainingTest, ClassifierLearnsToyTaskAndCamsPeakOnObjects) {
  MOSLAM_SHARED_OR_SKIP(weights, kWeights);
  const TrainSummary summary = TrainClassifier(ToyClassifier(data_, dir_.path() + "/cls", weights));
  ASSERT_TRUE(fs::exists(summary.model));
  EXPECT_TRUE(fs::exists(dir_.path() + "/cls/curve.png"));
  EXPECT_TRUE(fs::exists(dir_.path() + "/cls/preview/cam_0000.png"));
  net::ClassifierNet net = net::LoadClassifier(summary.model);
  net->eval();
  int correct = 0, total = 0, peaks_inside = 0, peaks = 0;
  for (size_t i = 0; i < toys_.size(); ++i) {
    const cv::Mat image = cv::imread(fmt::format("{}/images/{:03d}.png", data_, i));
    std::vector<float> scores;
    const cv::Mat cams = internal::ComputeCams(net, image, &scores);
    const bool truth[2] = {toys_[i].square, toys_[i].disc};
    const cv::Rect boxes[2] = {toys_[i].square_box, toys_[i].disc_box};
    for (int c = 0; c < 2; ++c) {
      correct += (scores[c] > 0.5f) == truth[c];
      ++total;
      if (!truth[c]) continue;
      cv::Point peak;
      cv::minMaxLoc(semantic::LabelPlane(cams, c), nullptr, nullptr, nullptr, &peak);
      // The CAM is computed at stride 8 and upsampled: allow one cell around the object.
      const cv::Rect grown(boxes[c].x - 8, boxes[c].y - 8, boxes[c].width + 16,
                           boxes[c].height + 16);
      peaks_inside += grown.contains(peak);
      ++peaks;
    }
  }
  EXPECT_GE(correct, total * 95 / 100) << correct << " of " << total << " labels right";
  EXPECT_GE(peaks_inside, peaks * 9 / 10) << peaks_inside << " of " << peaks << " CAM peaks";
}

TEST_F(TrainingTest, ALabelGridNeedsDataWithLabelImages) {
  // An image list has image-level labels only: no crop can be labelled, so a grid is refused
  // before anything is trained, naming the first image.
  ClassifierTrainOptions options = ToyClassifier(data_, dir_.path() + "/grid", "none");
  options.common.augment.label_grid_cols = 2;
  options.common.augment.label_grid_rows = 2;
  try {
    TrainClassifier(options);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), ::testing::HasSubstr("label grid"));
    EXPECT_THAT(e.what(), ::testing::HasSubstr("000.png"));
  }
}

TEST_F(TrainingTest, ResumeContinuesFromTheCheckpoint) {
  MOSLAM_SHARED_OR_SKIP(weights, kWeights);
  ClassifierTrainOptions options = ToyClassifier(data_, dir_.path() + "/resume", weights);
  options.common.epochs = 2;
  TrainClassifier(options);
  options.common.epochs = 3;
  options.common.resume = true;
  TrainClassifier(options);
  const nlohmann::json history =
      nlohmann::json::parse(std::ifstream(dir_.path() + "/resume/history.json"));
  ASSERT_EQ(history.size(), 3u);
  EXPECT_EQ(history[2]["epoch"], 3);
}

TEST_F(TrainingTest, CuesAndSegmenterRunEndToEnd) {
  MOSLAM_SHARED_OR_SKIP(weights, kWeights);
  const TrainSummary classifier =
      TrainClassifier(ToyClassifier(data_, dir_.path() + "/cls", weights));
  CueGenerationOptions cues;
  cues.data.list = data_ + "/list.txt";
  cues.data.classes = data_ + "/classes.txt";
  cues.colour_model = classifier.model;
  cues.out = dir_.path() + "/cues";
  cues.cues.superpixel_size = 6;
  cues.eval_labels = data_ + "/labels";
  cues.preview_images = 2;
  GenerateCues(cues);
  const nlohmann::json report = nlohmann::json::parse(std::ifstream(cues.out + "/cues.json"));
  EXPECT_THAT(report["classes"].get<std::vector<std::string>>(),
              ::testing::ElementsAre("square", "disc", "background"));
  EXPECT_GT(report["seeded_fraction"].get<double>(), 0.2);
  EXPECT_TRUE(fs::exists(cues.out + "/cues/000031.png"));

  SegmenterTrainOptions seg;
  seg.common = ToyOptions(data_, dir_.path() + "/seg");
  seg.common.epochs = 6;
  seg.cues = cues.out;
  seg.init_classifier = classifier.model;
  seg.net.backbone.last_block = 6;
  seg.net.backbone.output_stride = 8;
  seg.net.head_channels = 16;
  const TrainSummary summary = TrainSegmenter(seg);
  ASSERT_TRUE(fs::exists(summary.model));
  const nlohmann::json history =
      nlohmann::json::parse(std::ifstream(dir_.path() + "/seg/history.json"));
  ASSERT_EQ(history.size(), 6u);
  EXPECT_LT(history[5]["parts"]["seed"].get<double>(), history[0]["parts"]["seed"].get<double>());
  const net::SegmenterNet net = net::LoadSegmenter(summary.model);
  EXPECT_THAT(net->config().classes, ::testing::ElementsAre("square", "disc", "background"));
  EXPECT_THAT(net->config().movable, ::testing::ElementsAre("square"));
  EXPECT_EQ(net->config().background, "background");

  // A self-training round: cues from the segmenter and the CRF, of the same format and classes,
  // which a second segmenter (losses at stride 4, plain mean over seeds) trains on.
  CueGenerationOptions second = cues;
  second.colour_model.clear();
  second.segmenter_model = summary.model;
  second.out = dir_.path() + "/cues2";
  GenerateCues(second);
  const nlohmann::json report2 = nlohmann::json::parse(std::ifstream(second.out + "/cues.json"));
  EXPECT_EQ(report2["classes"], report["classes"]);
  EXPECT_GT(report2["seeded_fraction"].get<double>(), 0.2);
  EXPECT_GT(report2["class_fraction"]["square"].get<double>(), 0.0);
  EXPECT_GT(report2["class_fraction"]["disc"].get<double>(), 0.0);
  EXPECT_TRUE(fs::exists(second.out + "/cues/000031.png"));
  EXPECT_TRUE(fs::exists(second.out + "/preview/cues_0001.png"));
  seg.common.out = dir_.path() + "/seg2";
  seg.common.epochs = 2;
  seg.cues = second.out;
  seg.loss_stride = 4;
  seg.seed_balance = 0.0;
  seg.crf.appearance_weight = 2.0f;  // the constrain loss's CRF, as `--crf-config` sets it
  seg.crf.appearance_sxy = 10.0f;
  EXPECT_TRUE(fs::exists(TrainSegmenter(seg).model));
  const nlohmann::json seg2 = nlohmann::json::parse(std::ifstream(seg.common.out + "/report.json"));
  EXPECT_FLOAT_EQ(seg2["crf_appearance_weight"].get<float>(), 2.0f) << seg2.dump();
  EXPECT_FLOAT_EQ(seg2["crf_appearance_sxy"].get<float>(), 10.0f);
  // Where a labelled class is seeded on less than min_class_pixels of the image (here 99 %: every
  // image with two labels, and those with one unless the segmenter floods it), the image takes the
  // fallback cue, or none without one; other images keep the segmenter's cue.
  CueGenerationOptions raw = second;  // the segmenter's cue of every image, none replaced
  raw.out = dir_.path() + "/cues2raw";
  raw.min_class_pixels = 0.0f;
  GenerateCues(raw);
  CueGenerationOptions strict = second;
  strict.out = dir_.path() + "/cues3";
  strict.min_class_pixels = 0.99f;
  GenerateCues(strict);
  CueGenerationOptions fallback = strict;
  fallback.out = dir_.path() + "/cues4";
  fallback.fallback_cues = cues.out;
  GenerateCues(fallback);
  // Per class: only the missed classes' first-round seeds, over the segmenter's own cue.
  CueGenerationOptions per_class = fallback;
  per_class.out = dir_.path() + "/cues4c";
  per_class.fallback_per_class = true;
  GenerateCues(per_class);
  const auto cue = [](const std::string& folder, size_t i) {
    return cv::imread(fmt::format("{}/cues/{:06d}.png", folder, i), cv::IMREAD_UNCHANGED);
  };
  int missed = 0, changed_by_fill = 0;
  for (size_t i = 0; i < toys_.size(); ++i) {
    const cv::Mat own = cue(raw.out, i);
    const cv::Mat first_round = cue(cues.out, i);
    bool misses = false;
    cv::Mat filled = own.clone();
    for (const auto& [present, label] : {std::pair{toys_[i].square, 0}, {toys_[i].disc, 1}}) {
      if (present && cv::countNonZero(own == label) < 0.99 * own.total()) {
        misses = true;
        filled.setTo(label, first_round == label);
      }
    }
    missed += misses;
    const cv::Mat expected = misses ? cv::Mat(own.size(), CV_8UC1, cv::Scalar(kUnknown)) : own;
    EXPECT_EQ(cv::countNonZero(cue(strict.out, i) != expected), 0) << i;
    EXPECT_EQ(cv::countNonZero(cue(fallback.out, i) != (misses ? first_round : own)), 0) << i;
    EXPECT_EQ(cv::countNonZero(cue(per_class.out, i) != filled), 0) << i;
    if (misses) changed_by_fill += cv::countNonZero(filled != own);
  }
  EXPECT_GE(missed, 8);           // at least the images with both objects
  EXPECT_GT(changed_by_fill, 0);  // the fill did put first-round seeds in
  per_class.fallback_cues.clear();
  EXPECT_THAT(testing::ErrorOf([&] { GenerateCues(per_class); }),
              ::testing::HasSubstr("--fallback-per-class"));
  // RGB-D data: the CRF adds its depth kernel (objects 1 m in front of a background at 3 m, in
  // 16-bit PNGs of 1/5000 m named as the images).
  fs::create_directories(data_ + "/depth");
  for (size_t i = 0; i < toys_.size(); ++i) {
    const std::string name = fmt::format("{:03d}.png", i);
    const cv::Mat labels = cv::imread(data_ + "/labels/" + name, cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(labels.empty()) << name;
    cv::Mat depth(labels.size(), CV_16UC1, cv::Scalar(15000));
    depth.setTo(5000, labels > 0);
    cv::imwrite(data_ + "/depth/" + name, depth);
  }
  CueGenerationOptions with_depth = second;
  with_depth.out = dir_.path() + "/cues5";
  with_depth.depth_folder = data_ + "/depth";
  GenerateCues(with_depth);
  const nlohmann::json report5 =
      nlohmann::json::parse(std::ifstream(with_depth.out + "/cues.json"));
  EXPECT_EQ(report5["self_training"]["depth_folder"], with_depth.depth_folder);
  EXPECT_GT(report5["class_fraction"]["square"].get<double>(), 0.0);
  EXPECT_GT(report5["class_fraction"]["disc"].get<double>(), 0.0);
  fs::remove(data_ + "/depth/003.png");
  EXPECT_THAT(testing::ErrorOf([&] { GenerateCues(with_depth); }),
              ::testing::HasSubstr("depth/003.png"));
  // Test-time augmentation (scales and mirror images) is recorded with the cues.
  CueGenerationOptions augmented = second;
  augmented.out = dir_.path() + "/cues6";
  augmented.scales = {1.0, 1.5};
  augmented.flip = true;
  GenerateCues(augmented);
  const nlohmann::json report6 = nlohmann::json::parse(std::ifstream(augmented.out + "/cues.json"));
  EXPECT_EQ(report6["scales"], nlohmann::json({1.0, 1.5}));
  EXPECT_EQ(report6["flip"], true);
  EXPECT_GT(report6["class_fraction"]["square"].get<double>(), 0.0);
  augmented.scales = {0.1};
  EXPECT_THAT(testing::ErrorOf([&] { GenerateCues(augmented); }), ::testing::HasSubstr("scales"));
  // Classifier cues take the same augmentation (multi-scale CAMs), recorded alike.
  augmented.segmenter_model.clear();
  augmented.scales = {1.0, 1.5};
  augmented.colour_model = classifier.model;
  augmented.out = dir_.path() + "/cues7";
  GenerateCues(augmented);
  const nlohmann::json report7 = nlohmann::json::parse(std::ifstream(augmented.out + "/cues.json"));
  EXPECT_EQ(report7["scales"], nlohmann::json({1.0, 1.5}));
  EXPECT_GT(report7["class_fraction"]["square"].get<double>(), 0.0);
  // Depth is for self-training cues; classifier models and a segmenter together are an error.
  with_depth.segmenter_model.clear();
  with_depth.colour_model = classifier.model;
  EXPECT_THROW(GenerateCues(with_depth), InputError);
  second.colour_model = classifier.model;
  EXPECT_THROW(GenerateCues(second), InputError);
}

// Test-time augmentation of self-training cues: one view is the plain softmax, and the flipped
// mean is mirror-symmetric (the mean over an image and its mirror gives, on the mirrored image,
// the mirror of the same map), whatever the network.
TEST(AugmentedProbabilities, OneViewIsTheSoftmaxAndFlipIsMirrorSymmetric) {
  net::NetConfig config;
  config.kind = net::NetKind::kSegmenter;
  config.classes = {"square", "background"};
  config.background = "background";
  config.backbone.last_block = 6;
  config.backbone.output_stride = 8;
  config.head_channels = 8;
  config.decoder_block = 3;
  config.decoder_channels = 8;
  config.input_width = 64;
  config.input_height = 48;
  torch::manual_seed(3);
  net::SegmenterNet net(config);
  net->eval();
  torch::NoGradGuard no_grad;
  cv::Mat image(48, 64, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  const torch::Tensor one = internal::AugmentedProbabilities(net, image, {1.0}, false);
  ASSERT_EQ(one.sizes(), (std::vector<int64_t>{2, 48, 64}));
  const torch::Tensor softmax =
      torch::softmax(
          net::UpsampleBilinear(net->forward(ToInputTensor(image).unsqueeze(0)).logits, 48, 64), 1)
          .squeeze(0);
  EXPECT_TRUE(torch::allclose(one, softmax, 1e-5, 1e-6));

  const std::vector<double> scales = {1.0, 1.5};
  const torch::Tensor both = internal::AugmentedProbabilities(net, image, scales, true);
  cv::Mat mirrored;
  cv::flip(image, mirrored, 1);
  const torch::Tensor of_mirror = internal::AugmentedProbabilities(net, mirrored, scales, true);
  EXPECT_TRUE(torch::allclose(of_mirror, both.flip({2}), 1e-4, 1e-5));
  EXPECT_TRUE(torch::allclose(both.sum(0), torch::ones({48, 64}), 1e-4, 1e-5));
  EXPECT_FALSE(torch::allclose(both, one, 1e-3, 1e-3));  // the other views do count
}

// Multi-scale CAMs for classifier cues: one view is the ReLU'd CAM, the flipped mean is
// mirror-symmetric, and the other views change the maps.
TEST(AugmentedCams, OneViewIsTheReluCamAndFlipIsMirrorSymmetric) {
  net::NetConfig config;
  config.kind = net::NetKind::kClassifier;
  config.classes = {"square", "disc"};
  config.backbone.last_block = 6;
  config.backbone.output_stride = 8;
  config.input_width = 64;
  config.input_height = 48;
  torch::manual_seed(4);
  net::ClassifierNet net(config);
  net->eval();
  cv::Mat image(48, 64, CV_8UC3);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  const cv::Mat one = internal::AugmentedCams(net, image, {1.0}, false);
  ASSERT_EQ(one.dims, 3);
  EXPECT_EQ(one.size[0], 2);
  EXPECT_EQ(one.size[1], 48);
  EXPECT_EQ(one.size[2], 64);
  const cv::Mat plain = internal::ComputeCams(net, image, nullptr);
  const cv::Mat relu = cv::max(plain, 0.0f);
  EXPECT_LT(cv::norm(one, relu, cv::NORM_INF), 1e-5);
  EXPECT_GT(cv::countNonZero(plain.reshape(1, 1) < 0.0f), 0);  // the ReLU did something

  const std::vector<double> scales = {1.0, 1.5};
  const cv::Mat both = internal::AugmentedCams(net, image, scales, true);
  cv::Mat mirrored;
  cv::flip(image, mirrored, 1);
  const cv::Mat of_mirror = internal::AugmentedCams(net, mirrored, scales, true);
  for (int c = 0; c < 2; ++c) {
    cv::Mat flipped_back;
    cv::flip(semantic::LabelPlane(of_mirror, c), flipped_back, 1);
    EXPECT_LT(cv::norm(flipped_back, semantic::LabelPlane(both, c), cv::NORM_INF), 1e-4) << c;
  }
  EXPECT_GT(cv::norm(both, one, cv::NORM_INF), 1e-3);  // the other views do count
}

// A classifier trained at stride 8 (finer activation maps) starts a stride-16 segmenter: the
// backbone's weights are copied across strides, since dilation changes no weight's shape.
TEST_F(TrainingTest, SegmenterStartsFromAClassifierOfAnotherStride) {
  net::NetConfig config;
  config.kind = net::NetKind::kClassifier;
  config.classes = {"square", "disc"};
  config.movable = {"square"};
  config.input_width = 64;
  config.input_height = 48;
  config.backbone.last_block = 7;  // natural stride 16, dilated to 8
  config.backbone.output_stride = 8;
  torch::manual_seed(5);
  net::ClassifierNet classifier(config);
  const std::string classifier_path = dir_.path() + "/cls8.mnet";
  net::SaveClassifier(classifier_path, classifier);

  CueGenerationOptions cues;
  cues.data.list = data_ + "/list.txt";
  cues.data.classes = data_ + "/classes.txt";
  cues.colour_model = classifier_path;
  cues.out = dir_.path() + "/cues8";
  cues.cues.superpixel_size = 6;
  cues.preview_images = 0;
  GenerateCues(cues);

  SegmenterTrainOptions seg;
  seg.common = ToyOptions(data_, dir_.path() + "/seg16");
  seg.common.epochs = 1;
  seg.common.preview_images = 0;
  seg.cues = cues.out;
  seg.init_classifier = classifier_path;
  seg.net.backbone.last_block = 7;
  seg.net.backbone.output_stride = 16;
  seg.net.backbone.frozen_blocks = 8;  // all frozen: the copied weights stay as they were
  seg.net.head_channels = 16;
  net::SegmenterNet segmenter = net::LoadSegmenter(TrainSegmenter(seg).model);
  EXPECT_EQ(segmenter->config().backbone.output_stride, 16);
  auto source = classifier->backbone()->named_parameters();
  int compared = 0;
  for (const auto& item : segmenter->backbone()->named_parameters()) {
    // The segmenter is saved in float16.
    EXPECT_TRUE(torch::allclose(item.value().to(torch::kFloat32), source[item.key()], 1e-3, 1e-4))
        << item.key();
    ++compared;
  }
  EXPECT_GT(compared, 10);
}

}  // namespace
}  // namespace moslam::weak
