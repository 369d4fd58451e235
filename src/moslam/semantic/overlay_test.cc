#include "moslam/semantic/overlay.h"

#include <set>
#include <tuple>

#include <gtest/gtest.h>

namespace moslam::semantic {
namespace {

TEST(Overlay, LabelColoursAreDistinct) {
  std::set<std::tuple<double, double, double>> seen;
  for (int l = 0; l < 32; ++l) {
    const cv::Scalar c = LabelColour(l);
    seen.insert({c[0], c[1], c[2]});
  }
  EXPECT_EQ(seen.size(), 32u);
}

TEST(Overlay, BoundariesTakeTheLabelColourAndInteriorsAreBlended) {
  cv::Mat image(10, 12, CV_8UC1, cv::Scalar(100));
  cv::Mat labels(10, 12, CV_8U, cv::Scalar(0));
  labels(cv::Rect(6, 0, 6, 10)).setTo(3);
  const cv::Mat out = DrawLabelOverlay(image, labels, 0.5);
  ASSERT_EQ(out.type(), CV_8UC3);
  ASSERT_EQ(out.size(), image.size());
  const cv::Scalar zero = LabelColour(0);
  const cv::Scalar three = LabelColour(3);
  // x = 5 borders label 3 on its right: drawn in label 0's colour.
  for (int c = 0; c < 3; ++c) EXPECT_EQ(out.at<cv::Vec3b>(4, 5)[c], zero[c]);
  // Interior of label 3: half image, half colour.
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(out.at<cv::Vec3b>(4, 9)[c], 50 + 0.5 * three[c], 1);
}

TEST(Overlay, MaskOverlayAndPanels) {
  cv::Mat image(20, 30, CV_8UC3, cv::Scalar(0, 0, 0));
  cv::Mat mask(20, 30, CV_8U, cv::Scalar(0));
  mask(cv::Rect(10, 5, 10, 10)).setTo(1);
  const cv::Mat out = DrawMaskOverlay(image, mask, cv::Scalar(0, 0, 255), 0.5);
  EXPECT_EQ(out.at<cv::Vec3b>(5, 10), cv::Vec3b(0, 0, 255));  // outline
  EXPECT_EQ(out.at<cv::Vec3b>(10, 15)[2], 128);               // tinted inside
  EXPECT_EQ(out.at<cv::Vec3b>(2, 2), cv::Vec3b(0, 0, 0));     // untouched outside
  const cv::Mat panels = SideBySide({out, out}, {"before", "after"});
  EXPECT_EQ(panels.cols, 60);
  EXPECT_EQ(panels.rows, 20);
}

}  // namespace
}  // namespace moslam::semantic
