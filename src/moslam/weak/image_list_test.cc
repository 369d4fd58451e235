// Image lists of the weak pipeline: classes files, list round trip, error messages naming file,
// line and class, the synthetic generator's training folder, CamVid, crop labels, held-out split.
#include "moslam/weak/image_list.h"

#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::weak {
namespace {

namespace fs = std::filesystem;
using ::moslam::testing::ErrorOf;
using ::moslam::testing::TempDir;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

// The synthetic generator's classes.txt (synth/output_files.cc).
constexpr const char* kSynthClasses =
    "0 background 0\n1 person 1\n2 car 1\n3 chair 0\n4 tvmonitor 0\n5 diningtable 0\n";

// Writes a small image at dir/relative (creating folders) and returns its full path.
std::string WriteImage(const TempDir& dir, const std::string& relative) {
  const fs::path path = fs::path(dir.path()) / relative;
  fs::create_directories(path.parent_path());
  cv::imwrite(path.string(), cv::Mat(8, 8, CV_8UC3, cv::Scalar(10, 20, 30)));
  return path.string();
}

TEST(ImageListTest, ClassesFileMakesBackgroundSpecial) {
  TempDir dir;
  const ImageList list = ReadClassesFile(dir.Write("classes.txt", kSynthClasses));
  EXPECT_EQ(list.background, "background");
  EXPECT_THAT(list.class_names, ElementsAre("person", "car", "chair", "tvmonitor", "diningtable"));
  EXPECT_THAT(list.movable, ElementsAre(true, true, false, false, false));
  EXPECT_EQ(list.ClassIndex("chair"), 2);
  EXPECT_EQ(list.ClassIndex("background"), -1);
  EXPECT_EQ(list.ClassIndex("dog"), -1);
}

TEST(ImageListTest, ClassesFileErrorsNameFileAndLine) {
  TempDir dir;
  const std::string gap = dir.Write("gap.txt", "# id name movable\n0 a 0\n2 b 1\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassesFile(gap); }), HasSubstr("gap.txt:3"));
  const std::string bad = dir.Write("bad.txt", "0 a 0\n1 b 2\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassesFile(bad); }), HasSubstr("bad.txt:2"));
  const std::string twice = dir.Write("twice.txt", "0 a 0\n1 a 1\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassesFile(twice); }), HasSubstr("'a' repeated"));
  const std::string only_bg = dir.Write("bg.txt", "0 background 0\n");
  EXPECT_THAT(ErrorOf([&] { ReadClassesFile(only_bg); }), HasSubstr("no classes"));
}

TEST(ImageListTest, RoundTripKeepsImagesAndLabels) {
  TempDir dir;
  WriteImage(dir, "rgb/a.png");
  WriteImage(dir, "rgb/b.png");
  WriteImage(dir, "rgb/c.png");
  const ImageList classes = ReadClassesFile(dir.Write("classes.txt", kSynthClasses));
  // Unsorted and repeated names, the background name, comments, a line without classes.
  const std::string list_path =
      dir.Write("list.txt",
                "# a comment\n"
                "rgb/a.png chair person person\n"
                "\n"
                "rgb/b.png\n"
                "rgb/c.png background diningtable # trailing comment car\n");
  const ImageList list = ReadImageList(list_path, classes);
  ASSERT_EQ(list.entries.size(), 3u);
  EXPECT_EQ(list.entries[0].image, (fs::path(dir.path()) / "rgb/a.png").string());
  EXPECT_THAT(list.entries[0].classes, ElementsAre(0, 2));
  EXPECT_THAT(list.entries[1].classes, IsEmpty());
  EXPECT_THAT(list.entries[2].classes, ElementsAre(4));

  // Written into a sub folder: paths below it would be relative, these are not, so absolute.
  fs::create_directories(fs::path(dir.path()) / "out");
  const std::string out_path = (fs::path(dir.path()) / "out" / "list.txt").string();
  WriteImageList(out_path, list);
  const ImageList again = ReadImageList(out_path, classes);
  ASSERT_EQ(again.entries.size(), list.entries.size());
  for (size_t i = 0; i < list.entries.size(); ++i) {
    EXPECT_EQ(again.entries[i].image, list.entries[i].image);
    EXPECT_EQ(again.entries[i].classes, list.entries[i].classes);
  }
  // Written beside the images: relative paths, so the folder can be moved (copied here).
  WriteImageList((fs::path(dir.path()) / "list2.txt").string(), list);
  TempDir moved;
  fs::copy(dir.path(), moved.path(), fs::copy_options::recursive);
  const ImageList after_move = ReadImageList(moved.path() + "/list2.txt", classes);
  ASSERT_EQ(after_move.entries.size(), 3u);
  EXPECT_EQ(after_move.entries[2].image, moved.path() + "/rgb/c.png");
  EXPECT_THAT(after_move.entries[2].classes, ElementsAre(4));

  // The classes file round trip.
  const std::string classes_out = (fs::path(dir.path()) / "classes2.txt").string();
  WriteClassesFile(classes_out, classes);
  const ImageList classes_again = ReadClassesFile(classes_out);
  EXPECT_EQ(classes_again.class_names, classes.class_names);
  EXPECT_EQ(classes_again.movable, classes.movable);
  EXPECT_EQ(classes_again.background, classes.background);
}

TEST(ImageListTest, ErrorsNameFileLineAndClassOrImage) {
  TempDir dir;
  WriteImage(dir, "rgb/a.png");
  const ImageList classes = ReadClassesFile(dir.Write("classes.txt", kSynthClasses));
  const std::string unknown =
      dir.Write("unknown.txt", "# header\nrgb/a.png person\nrgb/a.png sofa\n");
  const std::string message = ErrorOf([&] { ReadImageList(unknown, classes); });
  EXPECT_THAT(message, HasSubstr("unknown.txt:3"));
  EXPECT_THAT(message, HasSubstr("'sofa'"));
  EXPECT_THAT(message, HasSubstr("person, car"));  // lists the known classes

  const std::string missing = dir.Write("missing.txt", "rgb/a.png\nrgb/nothere.png person\n");
  const std::string m2 = ErrorOf([&] { ReadImageList(missing, classes); });
  EXPECT_THAT(m2, HasSubstr("missing.txt:2"));
  EXPECT_THAT(m2, HasSubstr("rgb/nothere.png"));

  EXPECT_THAT(ErrorOf([&] { ReadImageList(dir.path() + "/none.txt", classes); }),
              HasSubstr("none.txt"));
}

TEST(ImageListTest, SyntheticTrainingFolder) {
  // The layout `moslam synth --train N` writes (docs/SYNTH.md; synth/output_files.cc).
  TempDir dir;
  WriteImage(dir, "rgb/000000.png");
  WriteImage(dir, "rgb/000001.png");
  dir.Write("classes.txt", kSynthClasses);
  dir.Write("labels.txt",
            "# image-level labels: <image> <classes with at least 200 pixels> (background not "
            "listed)\nrgb/000000.png person chair\nrgb/000001.png\n");
  const ImageList list = ReadSyntheticTraining(dir.path());
  EXPECT_EQ(list.background, "background");
  EXPECT_EQ(list.num_classes(), 5);
  ASSERT_EQ(list.entries.size(), 2u);
  EXPECT_THAT(list.entries[0].classes, ElementsAre(0, 2));
  EXPECT_THAT(list.entries[1].classes, IsEmpty());
  EXPECT_TRUE(list.entries[0].label_image.empty());
}

TEST(ImageListTest, SyntheticCropLabelsComeFromTheGeneratorsClassImages) {
  TempDir dir;
  WriteImage(dir, "rgb/000000.png");
  dir.Write("classes.txt", kSynthClasses);
  dir.Write("labels.txt", "rgb/000000.png person\n");
  const ImageList plain = ReadSyntheticTraining(dir.path(), false);
  EXPECT_TRUE(plain.entries[0].label_image.empty());
  EXPECT_TRUE(plain.label_to_class.empty());
  // Without the class image the request is refused, naming the missing file.
  EXPECT_THAT(ErrorOf([&] { ReadSyntheticTraining(dir.path(), true); }),
              HasSubstr("eval_only/class/000000.png"));
  fs::create_directories(fs::path(dir.path()) / "eval_only/class");
  cv::imwrite(dir.path() + "/eval_only/class/000000.png", cv::Mat(8, 8, CV_8UC1, cv::Scalar(1)));
  const ImageList list = ReadSyntheticTraining(dir.path(), true);
  ASSERT_EQ(list.entries.size(), 1u);
  EXPECT_EQ(fs::path(list.entries[0].label_image).lexically_normal(),
            (fs::path(dir.path()) / "eval_only/class/000000.png").lexically_normal());
  // Id 0 (background) is no class; ids 1..5 are classes 0..4 (person ... diningtable).
  EXPECT_THAT(list.label_to_class, ElementsAre(-1, 0, 1, 2, 3, 4));
  EXPECT_DOUBLE_EQ(list.label_min_fraction, kSyntheticLabelMinFraction);
  // Whole-image labels stay those of labels.txt.
  EXPECT_THAT(list.entries[0].classes, ElementsAre(0));
}

TEST(ImageListTest, SplitHoldoutTakesEveryKthEntry) {
  ImageList list;
  list.class_names = {"a"};
  list.movable = {false};
  for (int i = 0; i < 7; ++i) list.entries.push_back({std::to_string(i), {}, ""});
  const ImageList held = SplitHoldout(list, 3, true);
  const ImageList kept = SplitHoldout(list, 3, false);
  ASSERT_EQ(held.entries.size(), 2u);
  EXPECT_EQ(held.entries[0].image, "2");
  EXPECT_EQ(held.entries[1].image, "5");
  ASSERT_EQ(kept.entries.size(), 5u);
  EXPECT_EQ(kept.entries[2].image, "3");
  EXPECT_EQ(kept.class_names, list.class_names);
  EXPECT_THAT(ErrorOf([&] { SplitHoldout(list, 1, true); }), HasSubstr("every"));
}

TEST(CropLabelsTest, CropThatExcludesAnObjectDropsItsClass) {
  // 100 x 100 ids: class 0 everywhere, class 2 in a 10 x 10 block at (80, 80), unlabelled (11)
  // in the top-left corner.
  cv::Mat ids(100, 100, CV_8UC1, cv::Scalar(0));
  ids(cv::Rect(80, 80, 10, 10)).setTo(2);
  ids(cv::Rect(0, 0, 20, 20)).setTo(11);
  EXPECT_THAT(CropLabels(ids, cv::Rect(0, 0, 100, 100), 11), ElementsAre(0, 2));
  EXPECT_THAT(CropLabels(ids, cv::Rect(0, 0, 60, 60), 11), ElementsAre(0));
  EXPECT_THAT(CropLabels(ids, cv::Rect(85, 85, 15, 15), 11), ElementsAre(0, 2));
  // Only unlabelled pixels: no class.
  EXPECT_THAT(CropLabels(ids, cv::Rect(0, 0, 20, 20), 11), IsEmpty());
}

TEST(CropLabelsTest, MinFractionRuleAtTheBoundary) {
  // 0.1 % of 100 x 100 is 10 pixels: 10 make the class present, 9 do not.
  cv::Mat ids(100, 100, CV_8UC1, cv::Scalar(0));
  ids(cv::Rect(0, 0, 10, 1)).setTo(3);
  ids(cv::Rect(0, 50, 9, 1)).setTo(4);
  EXPECT_THAT(CropLabels(ids, cv::Rect(0, 0, 100, 100), 11, 0.001), ElementsAre(0, 3));
  // The same count relative to a smaller roi (50 x 100 = 5000 px, 5 needed): both present.
  EXPECT_THAT(CropLabels(ids, cv::Rect(0, 0, 50, 100), 11, 0.001), ElementsAre(0, 3, 4));
  // min_fraction 0 still needs a pixel.
  EXPECT_THAT(CropLabels(ids, cv::Rect(50, 0, 50, 100), 11, 0.0), ElementsAre(0));
}

TEST(CamVidTest, TrainAndValSplits) {
  MOSLAM_SHARED_OR_SKIP(root, "data/camvid");
  const ImageList train = ReadCamVid(root, "train");
  const ImageList val = ReadCamVid(root, "val");
  EXPECT_EQ(train.entries.size(), 367u);
  EXPECT_EQ(val.entries.size(), 101u);
  ASSERT_EQ(train.num_classes(), 11);
  EXPECT_EQ(train.class_names[3], "Road");
  EXPECT_TRUE(train.background.empty());
  EXPECT_THAT(train.movable, ElementsAre(false, false, false, false, false, false, false, false,
                                         true, true, true));
  const int road = train.ClassIndex("Road");
  int with_car = 0;
  for (const ImageListEntry& e : train.entries) {
    EXPECT_TRUE(fs::is_regular_file(e.image)) << e.image;
    EXPECT_TRUE(fs::is_regular_file(e.label_image)) << e.label_image;
    // Every training frame is a street scene from a car.
    EXPECT_NE(std::find(e.classes.begin(), e.classes.end(), road), e.classes.end()) << e.image;
    EXPECT_TRUE(std::is_sorted(e.classes.begin(), e.classes.end()));
    with_car += std::count(e.classes.begin(), e.classes.end(), train.ClassIndex("Car"));
  }
  // Cars are common but not everywhere: the label carries information.
  EXPECT_GT(with_car, 0);
  EXPECT_LT(with_car, 367);
  // A stricter rule never adds classes.
  const ImageList strict = ReadCamVid(root, "val", 0.05);
  for (size_t i = 0; i < val.entries.size(); ++i) {
    EXPECT_TRUE(std::includes(val.entries[i].classes.begin(), val.entries[i].classes.end(),
                              strict.entries[i].classes.begin(), strict.entries[i].classes.end()));
  }
  EXPECT_THAT(ErrorOf([&] { ReadCamVid(root, "nosuchsplit"); }), HasSubstr("nosuchsplit"));
}

}  // namespace
}  // namespace moslam::weak
