#include "moslam/feature/movable_mask.h"

#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/test_images.h"
#include "moslam/geometry/se3.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

using test::TestCamera;
camera::PinholeCamera Camera() { return TestCamera(); }

// A scene of a box face (the "person", a fronto-parallel rectangle x in [-0.3, 0.3], y in
// [-0.8, 0.8] of the world, 2 m in front of the first camera) before a wall at 4 m. Rendered for
// a camera at T_world_cam (rotation identity, looking down +z): depth and the box's mask.
struct View {
  cv::Mat depth, mask;
};
View Render(const Eigen::Vector3d& camera_centre) {
  const auto cam = Camera();
  View view{cv::Mat(480, 640, CV_32FC1), cv::Mat::zeros(480, 640, CV_8UC1)};
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const Eigen::Vector3d ray((u - cam.cx()) / cam.fx(), (v - cam.cy()) / cam.fy(), 1.0);
      const double z_box = 2.0 - camera_centre.z();
      const Eigen::Vector3d hit = camera_centre + z_box * ray;
      const bool on_box = std::abs(hit.x()) <= 0.3 && std::abs(hit.y()) <= 0.8;
      view.depth.at<float>(v, u) = static_cast<float>(on_box ? z_box : 4.0 - camera_centre.z());
      if (on_box) view.mask.at<uint8_t>(v, u) = 255;
    }
  }
  return view;
}

cv::Rect Bounds(const cv::Mat& mask) { return cv::boundingRect(mask); }

TEST(KeypointsNearMask, FlagsKeypointsWithinTheMargin) {
  cv::Mat mask = cv::Mat::zeros(100, 100, CV_8UC1);
  mask(cv::Rect(40, 40, 20, 20)).setTo(255);
  std::vector<cv::KeyPoint> keypoints = {
      cv::KeyPoint(50.f, 50.f, 7.f),  // inside
      cv::KeyPoint(63.f, 50.f, 7.f),  // 4 px right of the last mask column (59)
      cv::KeyPoint(65.f, 50.f, 7.f),  // 6 px
      cv::KeyPoint(10.f, 10.f, 7.f)};
  EXPECT_EQ(KeypointsNearMask(keypoints, mask, 4), (std::vector<uint8_t>{1, 1, 0, 0}));
  EXPECT_EQ(KeypointsNearMask(keypoints, mask, 0), (std::vector<uint8_t>{1, 0, 0, 0}));
  EXPECT_EQ(KeypointsNearMask(keypoints, cv::Mat(), 4), (std::vector<uint8_t>{0, 0, 0, 0}));
}

TEST(WarpMask, LandsOnTheObjectInTheSecondViewGivenTheExactPose) {
  const View first = Render(Eigen::Vector3d::Zero());
  // The second camera 0.15 m to the right and 0.3 m closer: the box moves ~45 px left in the
  // image and grows by 18 %.
  const Eigen::Vector3d centre(0.15, 0.0, 0.3);
  const View second = Render(centre);
  const geometry::SE3 T_world_second(Eigen::Matrix3d::Identity(), centre);
  const cv::Mat warped = WarpMask(first.mask, first.depth, Camera(), T_world_second.Inverse());
  const cv::Rect got = Bounds(warped), want = Bounds(second.mask);
  EXPECT_LE(std::abs(got.x - want.x), 2);
  EXPECT_LE(std::abs(got.y - want.y), 2);
  EXPECT_LE(std::abs(got.br().x - want.br().x), 2);
  EXPECT_LE(std::abs(got.br().y - want.br().y), 2);
  // No cracks: the splat fills the enlarged box.
  cv::Mat inside = second.mask.clone();
  cv::erode(inside, inside, cv::Mat(), cv::Point(-1, -1), 2);
  cv::Mat missed;
  cv::bitwise_and(inside, ~warped, missed);
  EXPECT_EQ(cv::countNonZero(missed), 0);
  // Without the translation (the camera did not move) the mask stays where it was.
  const cv::Mat same = WarpMask(first.mask, first.depth, Camera(), geometry::SE3());
  EXPECT_EQ(Bounds(same), cv::Rect(Bounds(first.mask).x, Bounds(first.mask).y,
                                   Bounds(first.mask).width + 1, Bounds(first.mask).height + 1));
}

TEST(WarpMask, CarriesValuesAndKeepsTheSmallest) {
  cv::Mat values = cv::Mat::zeros(480, 640, CV_8UC1);
  values(cv::Rect(100, 100, 10, 10)).setTo(3);
  values(cv::Rect(105, 100, 10, 10)).setTo(1);
  const cv::Mat out = WarpMask(values, cv::Mat(), Camera(), geometry::SE3());
  EXPECT_EQ(out.at<uint8_t>(105, 102), 3);
  EXPECT_EQ(out.at<uint8_t>(105, 107), 1);  // both land here; the smaller wins
  EXPECT_EQ(out.at<uint8_t>(50, 50), 0);
}

TEST(CompleteMaskByDepth, GrowsOverTheBodyAndStopsAtTheDepthEdge) {
  const View view = Render(Eigen::Vector3d::Zero());
  // The network found the box's upper half only, and missed a 6 px band at its left side.
  cv::Mat partial = view.mask.clone();
  const cv::Rect box = Bounds(view.mask);
  partial(cv::Rect(box.x, box.y + box.height / 2, box.width, box.height - box.height / 2)).setTo(0);
  partial(cv::Rect(box.x, box.y, 6, box.height)).setTo(0);
  MaskCompletionOptions options;
  options.max_grow_px = 12;
  const cv::Mat completed = CompleteMaskByDepth(partial, view.depth, options);
  // Never onto the wall behind (1 m further: a depth edge).
  cv::Mat on_wall;
  cv::bitwise_and(completed, ~view.mask, on_wall);
  EXPECT_EQ(cv::countNonZero(on_wall), 0);
  // The missed band is filled, and the lower half up to 12 px below the network's mask.
  EXPECT_EQ(completed.at<uint8_t>(box.y + 10, box.x + 1), 255);
  EXPECT_EQ(completed.at<uint8_t>(box.y + box.height / 2 + 11, box.x + box.width / 2), 255);
  EXPECT_EQ(completed.at<uint8_t>(box.y + box.height / 2 + 14, box.x + box.width / 2), 0);
  // Off: the input as 0/255.
  options.max_grow_px = 0;
  EXPECT_EQ(cv::countNonZero(CompleteMaskByDepth(partial, view.depth, options) != partial), 0);
  options.max_depth_range = 0.0;
  EXPECT_THROW(CompleteMaskByDepth(partial, view.depth, options), InputError);
}

// Pooling keeps every masked pixel's block, at even and odd sizes; bringing it back covers the
// input, and only the blocks it touched.
TEST(MaskScale, DownsampleKeepsAnyMaskedPixelAndUpsampleCoversIt) {
  for (const cv::Size size : {cv::Size(640, 480), cv::Size(641, 479)}) {
    for (const int factor : {2, 3}) {
      cv::Mat mask = cv::Mat::zeros(size, CV_8UC1);
      mask.at<uint8_t>(7, 9) = 1;  // one pixel, any non-zero value
      mask(cv::Rect(100, 50, 33, 21)).setTo(255);
      mask.at<uint8_t>(size.height - 1, size.width - 1) = 255;  // the last, partial block
      const cv::Mat small = DownsampleMask(mask, factor);
      ASSERT_EQ(small.cols, (size.width + factor - 1) / factor);
      ASSERT_EQ(small.rows, (size.height + factor - 1) / factor);
      EXPECT_EQ(small.at<uint8_t>(7 / factor, 9 / factor), 255);
      const cv::Mat back = UpsampleMask(small, factor, size);
      ASSERT_EQ(back.size(), size);
      EXPECT_EQ(cv::countNonZero(mask & ~back), 0) << size << " x" << factor;
      // Each masked block adds at most factor^2 pixels: the single pixel's block and the box's
      // edge blocks, nothing far away.
      const cv::Rect box = cv::boundingRect(back(cv::Rect(50, 30, 200, 100)));
      EXPECT_GE(box.x + 50, 100 - factor);
      EXPECT_LE(box.x + 50 + box.width, 133 + factor);
    }
  }
  EXPECT_TRUE(DownsampleMask(cv::Mat(), 2).empty());
}

TEST(MaskScale, DepthIsSampledAndTheCameraProjectsAtTheSmallScale) {
  cv::Mat depth(480, 640, CV_32FC1);
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) depth.at<float>(v, u) = static_cast<float>(u + 1000 * v);
  }
  const cv::Mat small = DownsampleDepth(depth, 2);
  ASSERT_EQ(small.size(), cv::Size(320, 240));
  EXPECT_EQ(small.at<float>(10, 20), depth.at<float>(20, 40));  // no averaging
  const camera::PinholeCamera full = Camera(), half = DownsampledCamera(full, 2);
  const Eigen::Vector3d p(0.3, -0.2, 2.5);
  const Eigen::Vector2d a = *full.ProjectPinhole(p), b = *half.ProjectPinhole(p);
  EXPECT_NEAR(b.x(), a.x() / 2.0, 1e-9);
  EXPECT_NEAR(b.y(), a.y() / 2.0, 1e-9);
}

}  // namespace
}  // namespace moslam::feature
