#include "moslam/net/torch_segmenter.h"

#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/net/model_file.h"
#include "moslam/testing/error_of.h"
#include "moslam/testing/shared_data.h"

namespace moslam::net {
namespace {

using ::moslam::testing::ErrorOf;
using ::testing::HasSubstr;

NetConfig SmallConfig() {
  NetConfig config;
  config.kind = NetKind::kSegmenter;
  config.classes = {"background", "car", "person"};
  config.movable = {"car", "person"};
  config.background = "background";
  config.backbone.last_block = 6;
  config.backbone.output_stride = 8;
  config.head_channels = 8;
  config.head_dilations = {2};
  config.input_width = 64;
  config.input_height = 48;
  return config;
}

cv::Mat RandomImage(int type) {
  cv::Mat image(90, 120, type);
  cv::randu(image, cv::Scalar::all(0), cv::Scalar::all(256));
  return image;
}

void ExpectProbabilities(const TorchSegmentation& s, int classes, int h, int w) {
  ASSERT_EQ(s.probabilities.dims, 3);
  ASSERT_EQ(s.probabilities.type(), CV_32F);
  EXPECT_EQ(s.probabilities.size[0], classes);
  EXPECT_EQ(s.probabilities.size[1], h);
  EXPECT_EQ(s.probabilities.size[2], w);
  const float* p = s.probabilities.ptr<float>();
  const int plane = h * w;
  for (int i = 0; i < plane; ++i) {
    float sum = 0.0f;
    for (int c = 0; c < classes; ++c) {
      ASSERT_GE(p[c * plane + i], 0.0f);
      sum += p[c * plane + i];
    }
    ASSERT_NEAR(sum, 1.0f, 1e-5f) << "pixel " << i;
  }
  ASSERT_EQ(static_cast<int>(s.class_scores.size()), classes);
  for (float score : s.class_scores) {
    EXPECT_GT(score, 0.0f);
    EXPECT_LT(score, 1.0f);
  }
}

TEST(TorchSegmenter, ProbabilitiesSumToOneForColourAndGrey) {
  TorchSegmenter segmenter{SegmenterNet(SmallConfig())};
  ExpectProbabilities(segmenter.Run(RandomImage(CV_8UC3)), 3, 6, 8);
  ExpectProbabilities(segmenter.Run(RandomImage(CV_8UC1)), 3, 6, 8);
  EXPECT_EQ(segmenter.config().classes.size(), 3u);
}

TEST(TorchSegmenter, FromAModelFileGivesTheNetworksOutput) {
  testing::TempDir dir;
  NetConfig config = SmallConfig();
  config.grey = true;
  SegmenterNet net(config);
  const std::string path = dir.path() + "/s.mnet";
  SaveSegmenter(path, net);
  TorchSegmenter from_file(path, 1), in_memory(net);
  const cv::Mat image = RandomImage(CV_8UC3);
  const TorchSegmentation a = from_file.Run(image), b = in_memory.Run(image);
  ExpectProbabilities(a, 3, 6, 8);
  EXPECT_EQ(cv::norm(a.probabilities, b.probabilities, cv::NORM_INF), 0.0);
  EXPECT_EQ(a.class_scores, b.class_scores);
}

TEST(TorchSegmenter, RunsAtAnotherInputSize) {
  TorchSegmenter segmenter{SegmenterNet(SmallConfig())};
  EXPECT_EQ(segmenter.input_size(), cv::Size(64, 48));
  segmenter.set_input_size({96, 72});  // stride 8: 12 x 9 cells instead of 8 x 6
  EXPECT_EQ(segmenter.input_size(), cv::Size(96, 72));
  ExpectProbabilities(segmenter.Run(RandomImage(CV_8UC3)), 3, 9, 12);
  EXPECT_EQ(segmenter.config().input_width, 64);  // the model's own config is unchanged
  EXPECT_THAT(ErrorOf([&] { segmenter.set_input_size({31, 72}); }), HasSubstr("32x32"));
}

TEST(TorchSegmenter, AClassifierFileIsRejected) {
  testing::TempDir dir;
  NetConfig config = SmallConfig();
  config.kind = NetKind::kClassifier;
  ClassifierNet classifier(config);
  const std::string path = dir.path() + "/c.mnet";
  SaveClassifier(path, classifier);
  EXPECT_THAT(ErrorOf([&] { TorchSegmenter segmenter(path); }), HasSubstr("not a segmenter"));
}

}  // namespace
}  // namespace moslam::net
