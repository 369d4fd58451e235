// Augmentation and batching: cue maps stay aligned with the augmented image, crops of images with
// a label image are relabelled by what they contain, a seed fixes the sample, grey samples have
// equal channels, tensors are RGB in [-1, 1].
#include "moslam/weak/augment.h"

#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"
#include "moslam/weak/cues.h"

namespace moslam::weak {
namespace {

namespace fs = std::filesystem;
using ::moslam::testing::ErrorOf;
using ::moslam::testing::TempDir;
using ::testing::ElementsAre;
using ::testing::HasSubstr;

constexpr int kCols = 200;
constexpr int kRows = 160;
// A green square off-centre (so that a flip that missed the cue would move it elsewhere).
const cv::Rect kSquare(30, 50, 40, 40);

// One entry: a grey image with a green square; the cue is 1 on the square, 0 on a band at the
// right edge, unknown elsewhere. Returns the list; `cue_path` receives the cue's path.
ImageList SquareList(const TempDir& dir, std::string* cue_path) {
  cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(100, 100, 100));
  image(kSquare).setTo(cv::Scalar(0, 220, 0));
  const std::string image_path = dir.path() + "/square.png";
  cv::imwrite(image_path, image);
  cv::Mat cue(kRows, kCols, CV_8UC1, cv::Scalar(kUnknown));
  cue(kSquare).setTo(1);
  cue(cv::Rect(kCols - 30, 0, 30, kRows)).setTo(0);
  *cue_path = dir.path() + "/cue.png";
  cv::imwrite(*cue_path, cue);
  ImageList list;
  list.class_names = {"wall", "square"};
  list.movable = {false, true};
  list.entries.push_back({image_path, {1}, ""});
  return list;
}

bool IsGreen(const cv::Vec3b& bgr) { return bgr[1] > bgr[2] + 60 && bgr[1] > bgr[0] + 60; }

AugmentOptions SmallOutput() {
  AugmentOptions options;
  options.output_width = 100;
  options.output_height = 80;
  return options;
}

// A grey image with a red object of class 1 ("car") at `object` on class 0 ("road"), its CamVid-
// style id image, and a one-entry list that carries the id image (so crops are relabelled).
ImageList RedObjectList(const TempDir& dir, const cv::Rect& object) {
  cv::Mat image(kRows, kCols, CV_8UC3, cv::Scalar(100, 100, 100));
  cv::Mat ids(kRows, kCols, CV_8UC1, cv::Scalar(0));
  image(object).setTo(cv::Scalar(0, 0, 255));
  ids(object).setTo(1);
  cv::imwrite(dir.path() + "/image.png", image);
  cv::imwrite(dir.path() + "/ids.png", ids);
  ImageList list;
  list.class_names = {"road", "car"};
  list.movable = {false, true};
  list.entries.push_back({dir.path() + "/image.png", {0, 1}, dir.path() + "/ids.png"});
  return list;
}

TEST(AugmentTest, CueStaysAlignedWithTheAugmentedImage) {
  TempDir dir;
  std::string cue_path;
  const ImageList list = SquareList(dir, &cue_path);
  AugmentOptions options = SmallOutput();
  options.crop_probability = 1.0;
  options.min_scale = 0.6;
  std::mt19937_64 rng(7);
  int flipped_like = 0;
  for (int trial = 0; trial < 40; ++trial) {
    const Sample s = LoadSample(list, 0, options, rng, true, cue_path);
    ASSERT_EQ(s.image.size(), cv::Size(100, 80));
    ASSERT_EQ(s.cue.size(), cv::Size(100, 80));
    ASSERT_EQ(s.cue.type(), CV_8UC1);
    // Interior pixels (1 px away from the cue region's border, where resampling blends) of each
    // cue label: 1 is green, 0 is not.
    for (const int label : {0, 1}) {
      cv::Mat region = s.cue == label;
      cv::erode(region, region, cv::Mat());
      for (int y = 0; y < region.rows; ++y) {
        for (int x = 0; x < region.cols; ++x) {
          if (!region.at<uint8_t>(y, x)) continue;
          ASSERT_EQ(IsGreen(s.image.at<cv::Vec3b>(y, x)), label == 1)
              << "trial " << trial << " pixel " << x << "," << y;
        }
      }
    }
    // The square starts in the left half; after a flip its cue lies mostly in the right half.
    cv::Mat ones = s.cue == 1;
    if (cv::countNonZero(ones(cv::Rect(50, 0, 50, 80))) >
        cv::countNonZero(ones(cv::Rect(0, 0, 50, 80))))
      ++flipped_like;
  }
  // Both flipped and unflipped samples were seen (flip probability 0.5, 40 trials).
  EXPECT_GT(flipped_like, 0);
  EXPECT_LT(flipped_like, 40);
}

TEST(AugmentTest, WithoutAugmentationTheWholeImageIsResized) {
  TempDir dir;
  std::string cue_path;
  const ImageList list = SquareList(dir, &cue_path);
  std::mt19937_64 rng(1);
  const Sample s = LoadSample(list, 0, SmallOutput(), rng, false, cue_path);
  cv::Mat expected;
  cv::resize(cv::imread(list.entries[0].image), expected, cv::Size(100, 80), 0, 0, cv::INTER_AREA);
  EXPECT_EQ(cv::norm(s.image, expected, cv::NORM_INF), 0.0);
  EXPECT_THAT(s.classes, ElementsAre(1));
  EXPECT_EQ(s.index, 0);
  // Square at (30, 50)-(70, 90) scales to (15, 25)-(35, 45).
  EXPECT_EQ(s.cue.at<uint8_t>(35, 25), 1);
  EXPECT_EQ(s.cue.at<uint8_t>(35, 5), kUnknown);
  EXPECT_EQ(s.cue.at<uint8_t>(35, 95), 0);
}

TEST(AugmentTest, CropsOfLabelledImagesAreRelabelledByWhatTheyContain) {
  // An object of class 1 (red) in the top-left corner of a class-0 image: crops that miss it
  // lose class 1, crops that contain any of it keep it (a 30-pixel column is above 0.1 %).
  TempDir dir;
  const ImageList list = RedObjectList(dir, cv::Rect(0, 0, 30, 30));
  AugmentOptions options = SmallOutput();
  options.crop_probability = 1.0;
  options.brightness = options.contrast = options.saturation = 0.0;
  std::mt19937_64 rng(3);
  int with_car = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const Sample s = LoadSample(list, 0, options, rng, true);
    cv::Mat channels[3];
    cv::split(s.image, channels);
    cv::Mat red_minus_green;
    cv::subtract(channels[2], channels[1], red_minus_green);  // saturates at 0
    const bool red = cv::countNonZero(red_minus_green > 60) > 0;
    const bool car = std::count(s.classes.begin(), s.classes.end(), 1) > 0;
    EXPECT_EQ(car, red) << "trial " << trial;
    EXPECT_EQ(std::count(s.classes.begin(), s.classes.end(), 0), 1);
    with_car += car;
  }
  EXPECT_GT(with_car, 0);
  EXPECT_LT(with_car, 50);
}

TEST(AugmentTest, LabelGridCellsAreLabelledByWhatTheyContainInTheSamplesFrame) {
  // Class 1 fills the left quarter of a class-0 image. With a 2x1 grid the whole image's left
  // cell holds both classes and its right cell class 0 only; flipped, the two cells swap; a crop
  // of the right three quarters has no class 1 anywhere.
  TempDir dir;
  ImageList list = RedObjectList(dir, cv::Rect(0, 0, kCols / 4, kRows));
  AugmentOptions options = SmallOutput();
  options.brightness = options.contrast = options.saturation = 0.0;
  options.label_grid_cols = 2;
  options.label_grid_rows = 1;
  options.crop_probability = 0.0;
  std::mt19937_64 rng(5);
  int flipped = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const Sample s = LoadSample(list, 0, options, rng, true);
    ASSERT_EQ(s.cell_classes.size(), 2u);
    // The red object is on the left of the sample unless it was flipped.
    const bool red_left = s.image.at<cv::Vec3b>(s.image.rows / 2, 2)[2] > 200;
    flipped += !red_left;
    EXPECT_THAT(s.cell_classes[red_left ? 0 : 1], ElementsAre(0, 1)) << "trial " << trial;
    EXPECT_THAT(s.cell_classes[red_left ? 1 : 0], ElementsAre(0)) << "trial " << trial;
  }
  EXPECT_GT(flipped, 0);
  EXPECT_LT(flipped, 20);
  // Crops: every cell's labels are those of its part of the crop, whatever the crop.
  options.crop_probability = 1.0;
  options.min_scale = 0.5;
  options.flip = false;
  for (int trial = 0; trial < 20; ++trial) {
    const Sample s = LoadSample(list, 0, options, rng, true);
    ASSERT_EQ(s.cell_classes.size(), 2u);
    for (int c = 0; c < 2; ++c) {
      const cv::Mat cell =
          s.image(cv::Rect(c * s.image.cols / 2, 0, s.image.cols / 2, s.image.rows));
      std::vector<cv::Mat> channels;
      cv::split(cell, channels);
      const bool red = cv::countNonZero(channels[2] - channels[1] > 60) > 0;
      EXPECT_EQ(std::count(s.cell_classes[c].begin(), s.cell_classes[c].end(), 1) > 0, red)
          << "trial " << trial << " cell " << c;
    }
  }
  // The batch carries them as N x C x rows x cols.
  options.crop_probability = 0.0;
  const Sample s = LoadSample(list, 0, options, rng, false);
  const Batch batch = MakeBatch({s, s}, 2, 1, 2);
  ASSERT_EQ(batch.cell_labels.sizes(), (std::vector<int64_t>{2, 2, 1, 2}));
  EXPECT_FLOAT_EQ(batch.cell_labels[1][1][0][0].item<float>(), 1.0f);
  EXPECT_FLOAT_EQ(batch.cell_labels[1][1][0][1].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(batch.cell_labels[1][0][0][1].item<float>(), 1.0f);
  EXPECT_FALSE(MakeBatch({s}, 2).cell_labels.defined());
  // Entries without a label image get no cell labels.
  list.entries[0].label_image.clear();
  EXPECT_TRUE(LoadSample(list, 0, options, rng, false).cell_classes.empty());
}

TEST(AugmentTest, SyntheticFramesWithCropLabelsGetGridCellsThroughKeptClasses) {
  // A generator training folder (classes.txt ids, 255 = unlabelled): a person (id 1) fills the
  // left quarter, a chair (id 3) the right quarter. Keeping only the person, the left cell of a
  // 2x1 grid holds it and the right cell nothing (the chair became background, not a class).
  TempDir dir;
  fs::create_directories(fs::path(dir.path()) / "rgb");
  fs::create_directories(fs::path(dir.path()) / "eval_only/class");
  cv::imwrite(dir.path() + "/rgb/000000.png", cv::Mat(kRows, kCols, CV_8UC3, cv::Scalar(90)));
  cv::Mat ids(kRows, kCols, CV_8UC1, cv::Scalar(0));
  ids(cv::Rect(0, 0, kCols / 4, kRows)).setTo(1);
  ids(cv::Rect(3 * kCols / 4, 0, kCols / 4, kRows)).setTo(3);
  ids(cv::Rect(kCols / 2, 0, 4, 4)).setTo(255);
  cv::imwrite(dir.path() + "/eval_only/class/000000.png", ids);
  dir.Write("classes.txt",
            "0 background 0\n1 person 1\n2 car 1\n3 chair 0\n4 tvmonitor 0\n5 diningtable 0\n");
  dir.Write("labels.txt", "rgb/000000.png person chair\n");
  const ImageList list = KeepClasses(ReadSyntheticTraining(dir.path(), true), {"person"});
  AugmentOptions options = SmallOutput();
  options.label_grid_cols = 2;
  options.label_grid_rows = 1;
  options.crop_probability = 0.0;
  options.flip = false;
  RequireLabelImages(list, options, "test");
  std::mt19937_64 rng(3);
  const Sample s = LoadSample(list, 0, options, rng, true);
  EXPECT_THAT(s.classes, ElementsAre(0));
  ASSERT_EQ(s.cell_classes.size(), 2u);
  EXPECT_THAT(s.cell_classes[0], ElementsAre(0));
  EXPECT_TRUE(s.cell_classes[1].empty());
  // Without crop labels the same folder cannot have a grid.
  const ImageList plain = KeepClasses(ReadSyntheticTraining(dir.path(), false), {"person"});
  EXPECT_THAT(ErrorOf([&] { RequireLabelImages(plain, options, "test"); }),
              HasSubstr("--synthetic-crop-labels"));
}

TEST(AugmentTest, ASeedFixesTheSample) {
  TempDir dir;
  std::string cue_path;
  const ImageList list = SquareList(dir, &cue_path);
  AugmentOptions options = SmallOutput();
  options.crop_probability = 1.0;
  auto draw = [&](uint64_t seed) {
    std::mt19937_64 rng(seed);
    LoadSample(list, 0, options, rng, true, cue_path);  // the second sample of the stream
    return LoadSample(list, 0, options, rng, true, cue_path);
  };
  const Sample a = draw(11);
  const Sample b = draw(11);
  EXPECT_EQ(cv::norm(a.image, b.image, cv::NORM_INF), 0.0);
  EXPECT_EQ(cv::norm(a.cue, b.cue, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.classes, b.classes);
  int differing = 0;
  for (uint64_t seed = 12; seed < 17; ++seed) {
    differing += cv::norm(draw(seed).image, a.image, cv::NORM_INF) > 0.0;
  }
  EXPECT_GT(differing, 0);
}

TEST(AugmentTest, GreyGivesEqualChannels) {
  TempDir dir;
  std::string cue_path;
  const ImageList list = SquareList(dir, &cue_path);
  AugmentOptions options = SmallOutput();
  options.grey = true;
  std::mt19937_64 rng(5);
  for (const bool augment : {false, true}) {
    const Sample s = LoadSample(list, 0, options, rng, augment);
    ASSERT_EQ(s.image.type(), CV_8UC3);
    std::vector<cv::Mat> channels;
    cv::split(s.image, channels);
    EXPECT_EQ(cv::norm(channels[0], channels[1], cv::NORM_INF), 0.0);
    EXPECT_EQ(cv::norm(channels[0], channels[2], cv::NORM_INF), 0.0);
    EXPECT_GT(cv::norm(channels[0], cv::NORM_INF), 0.0);
  }
}

TEST(AugmentTest, InputTensorIsRgbInMinusOneToOne) {
  cv::Mat bgr(2, 3, CV_8UC3, cv::Scalar(0, 128, 255));  // B 0, G 128, R 255
  bgr.at<cv::Vec3b>(1, 2) = cv::Vec3b(255, 0, 0);       // a blue pixel
  const torch::Tensor t = ToInputTensor(bgr);
  ASSERT_EQ(t.sizes(), (std::vector<int64_t>{3, 2, 3}));
  EXPECT_EQ(t.dtype(), torch::kFloat32);
  EXPECT_FLOAT_EQ(t[0][0][0].item<float>(), 1.0f);             // R
  EXPECT_NEAR(t[1][0][0].item<float>(), 0.5f / 127.5f, 1e-6);  // G: 128 / 127.5 - 1
  EXPECT_FLOAT_EQ(t[2][0][0].item<float>(), -1.0f);            // B
  EXPECT_FLOAT_EQ(t[2][1][2].item<float>(), 1.0f);
  EXPECT_FLOAT_EQ(t[0][1][2].item<float>(), -1.0f);
  const torch::Tensor grey = ToInputTensor(cv::Mat(2, 2, CV_8UC1, cv::Scalar(0)));
  ASSERT_EQ(grey.sizes(), (std::vector<int64_t>{3, 2, 2}));
  EXPECT_FLOAT_EQ(grey.max().item<float>(), -1.0f);
}

TEST(AugmentTest, BatchStacksImagesLabelsAndCues) {
  TempDir dir;
  std::string cue_path;
  const ImageList list = SquareList(dir, &cue_path);
  const AugmentOptions options = SmallOutput();
  std::mt19937_64 rng(9);
  std::vector<Sample> samples;
  for (int i = 0; i < 3; ++i) samples.push_back(LoadSample(list, 0, options, rng, true, cue_path));
  samples[1].classes = {0, 1};
  const Batch batch = MakeBatch(samples, 2);
  ASSERT_EQ(batch.images.sizes(), (std::vector<int64_t>{3, 3, 80, 100}));
  EXPECT_GE(batch.images.min().item<float>(), -1.0f);
  EXPECT_LE(batch.images.max().item<float>(), 1.0f);
  ASSERT_EQ(batch.labels.sizes(), (std::vector<int64_t>{3, 2}));
  EXPECT_EQ(batch.labels.dtype(), torch::kFloat32);
  EXPECT_FLOAT_EQ(batch.labels[0][0].item<float>(), 0.0f);
  EXPECT_FLOAT_EQ(batch.labels[0][1].item<float>(), 1.0f);
  EXPECT_FLOAT_EQ(batch.labels[1][0].item<float>(), 1.0f);
  ASSERT_TRUE(batch.cues.defined());
  ASSERT_EQ(batch.cues.sizes(), (std::vector<int64_t>{3, 80, 100}));
  EXPECT_EQ(batch.cues.dtype(), torch::kInt64);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(batch.cues[i][40][50].item<int64_t>(), samples[i].cue.at<uint8_t>(40, 50));
    EXPECT_EQ(batch.cues[i].eq(1).sum().item<int64_t>(), cv::countNonZero(samples[i].cue == 1));
  }
  EXPECT_EQ(batch.bgr.size(), 3u);
  EXPECT_THAT(batch.indices, ElementsAre(0, 0, 0));
  // Without cues the tensor stays undefined.
  for (Sample& s : samples) s.cue = cv::Mat();
  EXPECT_FALSE(MakeBatch(samples, 2).cues.defined());
}

TEST(AugmentTest, OptionsCheckNamesTheField) {
  AugmentOptions options;
  options.min_scale = 0.0;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("min_scale"));
  options = AugmentOptions();
  options.min_scale = 0.9;
  options.max_scale = 0.8;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("min_scale"));
  options = AugmentOptions();
  options.crop_probability = 1.5;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("crop_probability"));
  options = AugmentOptions();
  options.output_width = 0;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("output_width"));
  options = AugmentOptions();
  options.saturation = -0.1;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("saturation"));
  options = AugmentOptions();
  options.label_grid_cols = 3;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("label_grid_cols"));
  EXPECT_NO_THROW(AugmentOptions().Check());
}

TEST(AugmentTest, UnreadableImageOrMismatchedCueIsAnInputError) {
  TempDir dir;
  std::string cue_path;
  ImageList list = SquareList(dir, &cue_path);
  std::mt19937_64 rng(1);
  const std::string small_cue = dir.path() + "/small_cue.png";
  cv::imwrite(small_cue, cv::Mat(10, 10, CV_8UC1, cv::Scalar(0)));
  EXPECT_THAT(ErrorOf([&] { LoadSample(list, 0, SmallOutput(), rng, true, small_cue); }),
              HasSubstr("small_cue.png"));
  list.entries[0].image = dir.Write("not_an_image.png", "text");
  EXPECT_THAT(ErrorOf([&] { LoadSample(list, 0, SmallOutput(), rng, true); }),
              HasSubstr("not_an_image.png"));
}

TEST(AugmentTest, CamVidCropsKeepAtLeastOneClass) {
  MOSLAM_SHARED_OR_SKIP(root, "data/camvid");
  const ImageList val = ReadCamVid(root, "val");
  AugmentOptions options;
  options.crop_probability = 1.0;
  std::mt19937_64 rng(2);
  for (int i = 0; i < 5; ++i) {
    const Sample s = LoadSample(val, i * 20, options, rng, true);
    EXPECT_EQ(s.image.size(), cv::Size(320, 240));
    EXPECT_FALSE(s.classes.empty());
    EXPECT_TRUE(std::is_sorted(s.classes.begin(), s.classes.end()));
  }
}

}  // namespace
}  // namespace moslam::weak
