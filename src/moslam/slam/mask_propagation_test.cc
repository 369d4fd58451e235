#include "moslam/slam/mask_propagation.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::TestCamera;

cv::Mat Box(int x, int y, int w, int h) {
  cv::Mat m = cv::Mat::zeros(480, 640, CV_8UC1);
  m(cv::Rect(x, y, w, h)).setTo(255);
  return m;
}

TEST(MaskPropagator, CarriesTheMaskWithTheMotionAndFadesIt) {
  MaskPropagationOptions options;
  options.max_age = 2;
  options.grow_px = 0;
  MaskPropagator propagator(TestCamera(), options);
  const cv::Size size(640, 480);
  const cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(2.0));
  // Frame 0: the network sees a body.
  cv::Mat mask = propagator.MaskFor(Box(300, 200, 40, 80), size, std::nullopt);
  EXPECT_EQ(cv::countNonZero(mask), 40 * 80);
  propagator.Commit(depth);
  // Frame 1: no network; the camera moved 0.1 m to the right (points move -0.1 m in x):
  // 25 px left at 2 m.
  const geometry::SE3 T_cur_last(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0.0, 0.0));
  mask = propagator.MaskFor(cv::Mat(), size, T_cur_last);
  ASSERT_FALSE(mask.empty());
  const cv::Rect carried = cv::boundingRect(mask);
  EXPECT_NEAR(carried.x, 275, 1);
  EXPECT_NEAR(carried.width, 40, 2);
  propagator.Commit(depth);
  // Frame 2: carried once more (the second frame after the network's: max_age 2 keeps it).
  mask = propagator.MaskFor(cv::Mat(), size, T_cur_last);
  ASSERT_FALSE(mask.empty());
  EXPECT_NEAR(cv::boundingRect(mask).x, 250, 1);
  propagator.Commit(depth);
  // Frame 3: faded.
  EXPECT_TRUE(propagator.MaskFor(cv::Mat(), size, T_cur_last).empty());
  propagator.Commit(depth);
}

TEST(MaskPropagator, UnitesTheNetworkWithTheCarriedMaskAndGrowsIt) {
  MaskPropagationOptions options;
  options.grow_px = 3;
  MaskPropagator propagator(TestCamera(), options);
  const cv::Size size(640, 480);
  propagator.MaskFor(Box(100, 100, 20, 20), size, std::nullopt);
  propagator.Commit(cv::Mat());  // no depth: carried by the rotation (identity here)
  const cv::Mat mask = propagator.MaskFor(Box(400, 100, 20, 20), size, geometry::SE3());
  EXPECT_EQ(mask.at<uint8_t>(110, 410), 255);  // the network's
  EXPECT_EQ(mask.at<uint8_t>(110, 110), 255);  // carried
  EXPECT_EQ(mask.at<uint8_t>(110, 97), 255);   // carried and grown by 3 px
  EXPECT_EQ(mask.at<uint8_t>(110, 95), 0);
  EXPECT_EQ(mask.at<uint8_t>(110, 397), 0);  // the network's own mask is not grown
  propagator.Reset();
  EXPECT_TRUE(propagator.MaskFor(cv::Mat(), size, geometry::SE3()).empty());
}

// A body 2 m away before a wall at 4 m walks 60 px to the left while the camera stands still:
// the carried pixels where the wall now shows through are dropped (they would seed the mask's
// completion on the wall), those where the body still is are kept; the camera's own motion,
// with a static scene, drops nothing.
TEST(MaskPropagator, DropsCarriedPixelsWhereTheDepthShowsTheBodyLeft) {
  MaskPropagationOptions options;
  options.grow_px = 0;
  const cv::Size size(640, 480);
  const auto scene = [](int body_x) {
    cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(4.0f));
    depth(cv::Rect(body_x, 200, 100, 200)).setTo(2.0f);
    return depth;
  };
  for (const bool check : {true, false}) {
    options.depth_check = check;
    MaskPropagator propagator(TestCamera(), options);
    propagator.MaskFor(Box(300, 200, 100, 200), size, std::nullopt, scene(300));
    propagator.Commit(scene(300));
    const cv::Mat mask = propagator.MaskFor(cv::Mat(), size, geometry::SE3(), scene(240));
    ASSERT_FALSE(mask.empty());
    EXPECT_EQ(mask.at<uint8_t>(300, 320), 255) << "the body is still here";
    EXPECT_EQ(mask.at<uint8_t>(300, 380), check ? 0 : 255) << "the wall shows through here";
    // (The warp splats each pixel on 2x2: unchecked, the box gains a column and a row.)
    EXPECT_EQ(cv::countNonZero(mask), check ? 40 * 200 : 101 * 201);
  }
  // The camera moves 0.1 m to the right, nothing in the scene does: the carried mask lands on
  // the body, where the depths agree, and none of it is dropped.
  options.depth_check = true;
  MaskPropagator propagator(TestCamera(), options);
  const geometry::SE3 T_cur_last(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.1, 0.0, 0.0));
  propagator.MaskFor(Box(300, 200, 100, 200), size, std::nullopt, scene(300));
  propagator.Commit(scene(300));
  const cv::Mat mask = propagator.MaskFor(cv::Mat(), size, T_cur_last, scene(275));
  ASSERT_FALSE(mask.empty());
  // Exactly the body: the splat's extra column and row fall on the wall, 2 m behind.
  EXPECT_EQ(cv::countNonZero(mask), 100 * 200);
  EXPECT_NEAR(cv::boundingRect(mask).x, 275, 1);
}

TEST(MaskPropagator, OptionsAreChecked) {
  MaskPropagationOptions options;
  options.max_age = 0;
  EXPECT_THROW(MaskPropagator(TestCamera(), options), InputError);
  options = MaskPropagationOptions();
  options.depth_gap_m = -0.1;
  EXPECT_THROW(MaskPropagator(TestCamera(), options), InputError);
}

}  // namespace
}  // namespace moslam::slam
