// Mask sources through the run loop: a folder of mask files, the synthetic generator's class
// images with classes.txt, missing masks, dilation, and the masks reaching FrameInput.
#include "moslam/runner/mask_source.h"

#include <filesystem>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/io/dataset.h"
#include "moslam/runner/run_loop.h"
#include "moslam/runner/test_sequences.h"
#include "moslam/semantic/input_limits.h"
#include "moslam/testing/error_of.h"

namespace moslam::runner {
namespace {

namespace fs = std::filesystem;
using ::moslam::testing::ErrorOf;
using test::FakeTracker;
using test::kCols;
using test::kRows;
using ::testing::HasSubstr;

RunOptions Quiet() {
  RunOptions options;
  options.progress = false;
  return options;
}

// A mask with a w x h movable block in the top-left corner, stored as value `value`.
cv::Mat Block(int w, int h, uint8_t value = 255) {
  cv::Mat mask(kRows, kCols, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(0, 0, w, h)).setTo(value);
  return mask;
}

TEST(MaskSourceTest, FilesAreMatchedByStemAndReachTheTracker) {
  testing::TempDir data, masks_dir;
  test::MakeTum(data, 3);
  for (int i = 0; i < 3; ++i) {
    test::WriteImage(masks_dir, test::Stamp(i) + ".png", Block(4 + i, 2, 1));  // any non-zero
  }
  const io::Sequence seq = io::ReadDataset(data.path());
  MaskOptions options;
  options.kind = MaskSourceKind::kFiles;
  options.folder = masks_dir.path();
  const auto masks = MakeMaskSource(options, seq);
  EXPECT_EQ(MaskPathFor(masks_dir.path(), seq.frames[1]),
            (fs::path(masks_dir.path()) / (test::Stamp(1) + ".png")).string());
  FakeTracker tracker;
  const RunResult result = RunSequence(seq, tracker, *masks, Quiet());
  ASSERT_EQ(tracker.masks.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const cv::Mat& mask = tracker.masks[i];
    ASSERT_EQ(mask.type(), CV_8UC1);
    ASSERT_EQ(mask.size(), cv::Size(kCols, kRows));
    EXPECT_EQ(cv::countNonZero(mask), (4 + i) * 2);
    EXPECT_DOUBLE_EQ(result.frames[i].mask_fraction, (4.0 + i) * 2 / (kCols * kRows));
  }
}

TEST(MaskSourceTest, MissingMaskIsAnErrorNamingTheFileUnlessEmptyIsAllowed) {
  testing::TempDir data, masks_dir;
  test::MakeTum(data, 3);
  test::WriteImage(masks_dir, test::Stamp(0) + ".png", Block(3, 3));
  test::WriteImage(masks_dir, test::Stamp(2) + ".png", Block(3, 3));
  const io::Sequence seq = io::ReadDataset(data.path());
  MaskOptions options;
  options.kind = MaskSourceKind::kFiles;
  options.folder = masks_dir.path();
  FakeTracker tracker;
  const auto strict = MakeMaskSource(options, seq);
  const std::string missing = MaskPathFor(masks_dir.path(), seq.frames[1]);
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *strict, Quiet())); }),
              HasSubstr(missing + ": mask of frame 1"));

  options.missing_empty = true;
  const auto lenient = MakeMaskSource(options, seq);
  FakeTracker tracker2;
  const RunResult result = RunSequence(seq, tracker2, *lenient, Quiet());
  ASSERT_EQ(tracker2.masks.size(), 3u);
  EXPECT_EQ(cv::countNonZero(tracker2.masks[0]), 9);
  EXPECT_TRUE(tracker2.masks[1].empty());
  EXPECT_EQ(result.frames[1].mask_fraction, 0.0);
}

TEST(MaskSourceTest, WrongSizeAndMissingFolderAreErrors) {
  testing::TempDir data, masks_dir;
  test::MakeTum(data, 1);
  test::WriteImage(masks_dir, test::Stamp(0) + ".png", cv::Mat(4, 4, CV_8UC1, cv::Scalar(0)));
  const io::Sequence seq = io::ReadDataset(data.path());
  MaskOptions options;
  options.kind = MaskSourceKind::kFiles;
  options.folder = masks_dir.path();
  const auto masks = MakeMaskSource(options, seq);
  EXPECT_THAT(ErrorOf([&] { masks->MaskFor(seq.frames[0], cv::Size(kCols, kRows)); }),
              HasSubstr("is 4x4 but the frame's image is 24x16"));
  options.folder = masks_dir.path() + "/nope";
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, seq); }), HasSubstr("nope"));
}

TEST(MaskSourceTest, DilationGrowsTheMask) {
  testing::TempDir data, masks_dir;
  test::MakeTum(data, 1);
  cv::Mat dot(kRows, kCols, CV_8UC1, cv::Scalar(0));
  dot.at<uint8_t>(8, 12) = 255;
  test::WriteImage(masks_dir, test::Stamp(0) + ".png", dot);
  const io::Sequence seq = io::ReadDataset(data.path());
  MaskOptions options;
  options.kind = MaskSourceKind::kFiles;
  options.folder = masks_dir.path();
  options.dilate_px = 2;
  const FrameMask mask =
      MakeMaskSource(options, seq)->MaskFor(seq.frames[0], cv::Size(kCols, kRows));
  cv::Mat expected;
  cv::dilate(dot, expected, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(5, 5)));
  EXPECT_EQ(cv::countNonZero(mask.mask != expected), 0);
  EXPECT_GT(cv::countNonZero(mask.mask), 1);
}

// The synthetic generator's layout on top of a TUM-layout sequence: class/<stem>.png beside
// rgb/<stem>.png and classes.txt in the root.
void AddClassImages(const testing::TempDir& data, int frames) {
  data.Write("classes.txt", "# id name movable\n0 background 0\n3 person 1\n7 car 1\n9 tree 0\n");
  for (int i = 0; i < frames; ++i) {
    cv::Mat classes(kRows, kCols, CV_8UC1, cv::Scalar(0));
    classes(cv::Rect(0, 0, 2, 2)).setTo(3);   // 4 person pixels
    classes(cv::Rect(10, 0, 3, 2)).setTo(7);  // 6 car pixels
    classes(cv::Rect(0, 10, 5, 2)).setTo(9);  // 10 tree pixels
    test::WriteImage(data, "class/" + test::Stamp(i) + ".png", classes);
  }
}

TEST(MaskSourceTest, SynthGroundTruthUsesMovableClasses) {
  testing::TempDir data;
  test::MakeTum(data, 2);
  AddClassImages(data, 2);
  const io::Sequence seq = io::ReadDataset(data.path());
  MaskOptions options;
  options.kind = MaskSourceKind::kSynthGt;
  {
    const auto masks = MakeMaskSource(options, seq);  // default: classes.txt's movable ones
    EXPECT_EQ(masks->Describe(), "synth-gt (movable: person, car)");
    FakeTracker tracker;
    RunSequence(seq, tracker, *masks, Quiet());
    ASSERT_EQ(tracker.masks.size(), 2u);
    EXPECT_EQ(cv::countNonZero(tracker.masks[1]), 10);
  }
  options.movable = {"car", "tree"};
  const FrameMask mask =
      MakeMaskSource(options, seq)->MaskFor(seq.frames[0], cv::Size(kCols, kRows));
  EXPECT_EQ(cv::countNonZero(mask.mask), 16);
  EXPECT_EQ(mask.mask.at<uint8_t>(0, 10), 255);
  EXPECT_EQ(mask.mask.at<uint8_t>(0, 0), 0);
  options.movable = {"bus"};
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, seq); }),
              HasSubstr("no class named 'bus' (classes: background, person, car, tree)"));
}

TEST(MaskSourceTest, SynthGroundTruthNeedsItsFiles) {
  testing::TempDir data;
  test::MakeTum(data, 2);
  const io::Sequence seq = io::ReadDataset(data.path());
  MaskOptions options;
  options.kind = MaskSourceKind::kSynthGt;
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, seq); }), HasSubstr("classes.txt"));
  AddClassImages(data, 1);  // frame 1 has no class image
  const auto masks = MakeMaskSource(options, seq);
  FakeTracker tracker;
  EXPECT_THAT(ErrorOf([&] { RethrowFailure(RunSequence(seq, tracker, *masks, Quiet())); }),
              HasSubstr("class/" + test::Stamp(1) + ".png: class image of frame 1"));
}

TEST(MaskSourceTest, OptionsAreChecked) {
  MaskOptions options;
  options.dilate_px = -1;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("--mask-dilate"));
  // Issue 31: --mask-dilate 5000 ran for minutes a frame; the bound is refused up front.
  options.dilate_px = 5000;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }),
              ::testing::AllOf(HasSubstr("--mask-dilate"), HasSubstr("5000"),
                               HasSubstr(std::to_string(semantic::kMaxDilatePx))));
  options.dilate_px = semantic::kMaxDilatePx;
  EXPECT_NO_THROW(options.Check());
  options = {};
  options.kind = MaskSourceKind::kFiles;
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("--mask-source files"));
  options = {};
  options.movable = {"car"};
  EXPECT_THAT(ErrorOf([&] { options.Check(); }), HasSubstr("--movable"));
  EXPECT_EQ(ParseMaskSourceKind("synth-gt"), MaskSourceKind::kSynthGt);
  EXPECT_FALSE(ParseMaskSourceKind("gt").has_value());
}

}  // namespace
}  // namespace moslam::runner

namespace moslam::runner {
namespace {

TEST(MaskSourceTest, NetworkSourcesCheckTheirOptionsAndTheCardsKind) {
  const io::Sequence none;
  MaskOptions options;
  options.kind = MaskSourceKind::kOnnx;
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, none); }), HasSubstr("--model-card"));
  options.kind = MaskSourceKind::kNone;
  options.crf = semantic::CrfMode::kColour;
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, none); }), HasSubstr("--crf"));
  EXPECT_EQ(ParseMaskSourceKind("onnx"), MaskSourceKind::kOnnx);
  EXPECT_EQ(ParseMaskSourceKind("detector"), MaskSourceKind::kDetector);
  EXPECT_STREQ(ToString(MaskSourceKind::kDetector), "detector");
  EXPECT_EQ(ParseMaskSourceKind("model"), MaskSourceKind::kModel);
  EXPECT_STREQ(ToString(MaskSourceKind::kModel), "model");

  // A torch card is only for --mask-source model, and model only takes torch cards; the kinds
  // are checked before any model file is read.
  testing::TempDir dir;
  dir.Write("net.mnet", "not read");
  options = MaskOptions();
  options.kind = MaskSourceKind::kOnnx;
  options.model_card = dir.Write("torch.yaml", "%YAML:1.0\ntype: torch\nmodel: net.mnet\n");
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, none); }),
              ::testing::AllOf(HasSubstr("torch.yaml"), HasSubstr("--mask-source model")));
  options.kind = MaskSourceKind::kModel;
  options.model_card = dir.Write("onnx.yaml",
                                 "%YAML:1.0\ntype: segmentation\nmodel: net.mnet\n"
                                 "input_width: 64\ninput_height: 64\nclasses: [a, b]\n"
                                 "movable: [b]\n");
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, none); }),
              ::testing::AllOf(HasSubstr("onnx.yaml"), HasSubstr("torch card")));

  MOSLAM_SHARED_OR_SKIP(model, "models/deeplabv3_mnv2_voc/deeplabv3_mnv2_voc.onnx");
  options = MaskOptions();
  options.kind = MaskSourceKind::kDetector;
  options.model_card = "configs/models/deeplabv3_mnv2_voc.yaml";
  EXPECT_THAT(ErrorOf([&] { MakeMaskSource(options, none); }),
              ::testing::AllOf(HasSubstr("deeplabv3_mnv2_voc.yaml"), HasSubstr("detector")));
}

}  // namespace
}  // namespace moslam::runner
