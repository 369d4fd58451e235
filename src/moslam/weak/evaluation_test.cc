#include "moslam/weak/evaluation.h"

#include <cmath>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "moslam/util/error.h"

namespace moslam::weak {
namespace {

cv::Mat Ids(int rows, int cols, std::initializer_list<int> values) {
  cv::Mat m(rows, cols, CV_8U);
  auto it = values.begin();
  for (int y = 0; y < rows; ++y) {
    for (int x = 0; x < cols; ++x) m.at<uint8_t>(y, x) = static_cast<uint8_t>(*it++);
  }
  return m;
}

TEST(SegEvaluator, PerClassIoUAndMeanByHand) {
  SegEvalOptions options;
  options.ignore_labels = {};
  SegEvaluator eval({"a", "b", "c"}, options);
  eval.Add(Ids(2, 3, {0, 1, 1, 1, 2, 0}), Ids(2, 3, {0, 0, 1, 1, 2, 2}));
  // truth a: predicted a, b; truth b: b, b; truth c: c, a.
  const std::vector<double> iou = eval.ClassIoU();
  ASSERT_EQ(iou.size(), 3u);
  EXPECT_DOUBLE_EQ(iou[0], 1.0 / 3.0);  // 1 / (2 truth + 2 predicted - 1)
  EXPECT_DOUBLE_EQ(iou[1], 2.0 / 3.0);  // 2 / (2 + 3 - 2)
  EXPECT_DOUBLE_EQ(iou[2], 1.0 / 2.0);  // 1 / (2 + 1 - 1)
  EXPECT_DOUBLE_EQ(eval.MeanIoU(), 0.5);
  EXPECT_DOUBLE_EQ(eval.PixelAccuracy(), 4.0 / 6.0);
  EXPECT_DOUBLE_EQ(eval.confusion().at<double>(0, 1), 1.0);
  EXPECT_DOUBLE_EQ(eval.confusion().at<double>(2, 0), 1.0);
  EXPECT_DOUBLE_EQ(cv::sum(eval.confusion())[0], 6.0);
}

TEST(SegEvaluator, IgnoredLabelsAndMappingWithoutCounterpart) {
  SegEvalOptions options;
  options.ignore_labels = {4};
  options.label_to_class = {0, 1, -1, 0};  // label 2: no class; label 3: class 0
  SegEvaluator eval({"x", "y"}, options);
  // labels 0 1 2 3 4 4 -> truth x, y, none, x, ignored, ignored.
  eval.Add(Ids(1, 6, {0, 0, 1, 0, 1, 0}), Ids(1, 6, {0, 1, 2, 3, 4, 4}));
  EXPECT_DOUBLE_EQ(eval.confusion().at<double>(0, 0), 2.0);
  EXPECT_DOUBLE_EQ(eval.confusion().at<double>(1, 0), 1.0);
  EXPECT_DOUBLE_EQ(cv::sum(eval.confusion())[0], 3.0);
  EXPECT_DOUBLE_EQ(eval.unmatched().at<double>(0, 1), 1.0);
  const std::vector<double> iou = eval.ClassIoU();
  EXPECT_DOUBLE_EQ(iou[0], 2.0 / 3.0);  // 2 / (2 truth + 3 predicted - 2)
  EXPECT_DOUBLE_EQ(iou[1], 0.0);        // 0 / (1 truth + 1 predicted, the unmatched pixel)
  EXPECT_DOUBLE_EQ(eval.PixelAccuracy(), 0.5);
  const nlohmann::json json = eval.ToJson();
  EXPECT_DOUBLE_EQ(json["ignored_pixels"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(json["unmatched_label_pixels"][1].get<double>(), 1.0);
}

TEST(SegEvaluator, IdentityMappingLeavesLabelsBeyondTheClassesUnmatched) {
  SegEvalOptions options;
  options.ignore_labels = {};
  SegEvaluator eval({"x", "y"}, options);
  eval.Add(Ids(1, 2, {0, 0}), Ids(1, 2, {0, 7}));
  EXPECT_DOUBLE_EQ(eval.ClassIoU()[0], 0.5);
  EXPECT_DOUBLE_EQ(eval.unmatched().at<double>(0, 0), 1.0);
}

TEST(SegEvaluator, BinaryMovableScoresByHand) {
  SegEvalOptions options;  // ignores 11 by default
  options.movable_classes = {false, true, true};
  SegEvaluator eval({"road", "car", "person"}, options);
  // (truth, predicted) movable: FF, FT, TT, TF / TT, TT (person seen as car), ignored, FT.
  const double first = eval.Add(Ids(2, 4, {0, 1, 1, 0, 2, 1, 1, 1}),  // prediction
                                Ids(2, 4, {0, 0, 1, 1, 2, 2, 11, 0}));
  EXPECT_DOUBLE_EQ(first, 3.0 / 6.0);
  // An image without movable pixels in truth or prediction scores 1 and adds nothing.
  EXPECT_DOUBLE_EQ(eval.Add(Ids(1, 2, {0, 0}), Ids(1, 2, {0, 0})), 1.0);
  EXPECT_DOUBLE_EQ(eval.MovableIoU(), 0.5);
  EXPECT_DOUBLE_EQ(eval.MovablePrecision(), 3.0 / 5.0);
  EXPECT_DOUBLE_EQ(eval.MovableRecall(), 3.0 / 4.0);
  EXPECT_EQ(eval.images(), 2);
}

TEST(SegEvaluator, ExplicitMovableLabelsOverrideTheClasses) {
  SegEvalOptions options;
  options.movable_classes = {false, true, true};
  options.movable_labels = {false, true, false};  // label 2 (person) is not movable truth here
  SegEvaluator eval({"road", "car", "person"}, options);
  eval.Add(Ids(2, 4, {0, 1, 1, 0, 2, 1, 1, 1}), Ids(2, 4, {0, 0, 1, 1, 2, 2, 11, 0}));
  // tp: (0,2); fp: (0,1), (1,0), (1,1), (1,3); fn: (0,3).
  EXPECT_DOUBLE_EQ(eval.MovableIoU(), 1.0 / 6.0);
  EXPECT_DOUBLE_EQ(eval.MovablePrecision(), 1.0 / 5.0);
  EXPECT_DOUBLE_EQ(eval.MovableRecall(), 1.0 / 2.0);
}

TEST(SegEvaluator, AbsentClassesAreNaNAndLeftOutOfTheMean) {
  SegEvalOptions options;
  options.ignore_labels = {};
  SegEvaluator eval({"a", "b", "c", "d"}, options);
  eval.Add(Ids(1, 2, {0, 2}), Ids(1, 2, {0, 0}));
  const std::vector<double> iou = eval.ClassIoU();
  EXPECT_DOUBLE_EQ(iou[0], 0.5);
  EXPECT_TRUE(std::isnan(iou[1]));
  EXPECT_DOUBLE_EQ(iou[2], 0.0);  // predicted but absent from the truth: a miss, not NaN
  EXPECT_TRUE(std::isnan(iou[3]));
  EXPECT_DOUBLE_EQ(eval.MeanIoU(), 0.25);
  // No movable class at all: precision and recall are undefined, the IoU of nothing is 1.
  EXPECT_TRUE(std::isnan(eval.MovablePrecision()));
  EXPECT_TRUE(std::isnan(eval.MovableRecall()));
  EXPECT_DOUBLE_EQ(eval.MovableIoU(), 1.0);
  const nlohmann::json json = eval.ToJson();
  EXPECT_TRUE(json["classes"][1]["iou"].is_null());
  EXPECT_DOUBLE_EQ(json["classes"][2]["iou"].get<double>(), 0.0);
  EXPECT_DOUBLE_EQ(json["mean_iou"].get<double>(), 0.25);
  EXPECT_TRUE(json["movable"]["precision"].is_null());
  EXPECT_EQ(json["confusion"].size(), 4u);
  EXPECT_DOUBLE_EQ(json["confusion"][0][2].get<double>(), 1.0);
}

TEST(SegEvaluator, NoImagesGivesNaNMean) {
  SegEvaluator eval({"a", "b"}, {});
  EXPECT_TRUE(std::isnan(eval.MeanIoU()));
}

TEST(SegEvaluator, BadInputIsAnInputError) {
  SegEvaluator eval({"a", "b"}, {});
  EXPECT_THROW(eval.Add(Ids(1, 2, {0, 2}), Ids(1, 2, {0, 0})), InputError);  // class 2 of 2
  EXPECT_THROW(eval.Add(Ids(1, 2, {0, 1}), Ids(2, 1, {0, 0})), InputError);  // sizes
  SegEvalOptions bad;
  bad.label_to_class = {0, 5};
  EXPECT_THROW(SegEvaluator({"a", "b"}, bad), InputError);
  SegEvalOptions flags;
  flags.movable_classes = {true};
  EXPECT_THROW(SegEvaluator({"a", "b"}, flags), InputError);
}

TEST(LabelToClassByName, MatchesNamesAndSendsTheRestToTheBackground) {
  const std::vector<std::string>& camvid = CamVidLabelNames();
  ASSERT_EQ(camvid.size(), 11u);
  // The CamVid classes themselves: the identity, written out.
  const std::vector<int> same = LabelToClassByName(camvid, camvid, -1);
  for (int id = 0; id < 11; ++id) EXPECT_EQ(same[id], id);
  // A synthetic-style model: background, car, pedestrian (case-insensitive).
  const std::vector<int> few = LabelToClassByName(camvid, {"background", "car", "PEDESTRIAN"}, 0);
  EXPECT_EQ(few[8], 1);   // Car
  EXPECT_EQ(few[9], 2);   // Pedestrian
  EXPECT_EQ(few[0], 0);   // Sky -> background
  EXPECT_EQ(few[10], 0);  // Bicyclist -> background
  EXPECT_EQ(LabelToClassByName(camvid, {"car", "person"}, -1)[10], -1);
  EXPECT_TRUE(LabelToClassByName(camvid, {"a", "b"}, 0).empty());  // nothing in common
}

TEST(RenderConfusion, CellsAreShadedByRowShareAndEmptyRowsGrey) {
  cv::Mat confusion = cv::Mat::zeros(3, 3, CV_64F);
  confusion.at<double>(0, 0) = 10;  // row 0: all correct
  confusion.at<double>(1, 0) = 5;   // row 1: half and half
  confusion.at<double>(1, 1) = 5;   // row 2: no ground truth
  const cv::Mat image = RenderConfusion(confusion, {"Sky", "Building", "Car"});
  ASSERT_EQ(image.type(), CV_8UC3);
  EXPECT_GT(image.cols, 3 * 44);
  EXPECT_GT(image.rows, 3 * 44);
  cv::Mat full, grey;
  cv::inRange(image, cv::Scalar(255, 80, 30), cv::Scalar(255, 80, 30), full);
  cv::inRange(image, cv::Scalar(215, 215, 215), cv::Scalar(215, 215, 215), grey);
  EXPECT_GT(cv::countNonZero(full), 40 * 40 / 2);  // the one 100 % cell (minus its text)
  EXPECT_GT(cv::countNonZero(grey), 3 * 40 * 40);  // the three cells of the empty row
  EXPECT_THROW(RenderConfusion(confusion, {"a", "b"}), InputError);
}

}  // namespace
}  // namespace moslam::weak
