#include "moslam/slam/frame_mask.h"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/movable_mask.h"
#include "moslam/feature/structure_planes.h"
#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::TestCamera;

// A wall 3.5 m away, the floor 1.2 m below the camera, a body 2 m away standing on it, and the
// network's mask on the body's upper three quarters (the legs missed).
struct Scene {
  cv::Mat depth = cv::Mat(480, 640, CV_32FC1, cv::Scalar(3.5f));
  cv::Mat network = cv::Mat::zeros(480, 640, CV_8UC1);
  cv::Mat body = cv::Mat::zeros(480, 640, CV_8UC1);
  Scene() {
    for (int v = 241; v < 480; ++v) {
      depth.row(v).setTo(std::min(3.5f, static_cast<float>(1.2 * 500.0 / (v - 240))));
    }
    depth(cv::Rect(250, 60, 160, 340)).setTo(2.0f);  // feet at v = 400: the floor's 2 m row
    body(cv::Rect(250, 60, 160, 340)).setTo(255);
    network(cv::Rect(250, 60, 160, 255)).setTo(255);
  }
};

FrameMaskOptions Options(int scale) {
  FrameMaskOptions o;
  o.work_scale = scale;
  return o;
}

int Count(const cv::Mat& m) { return m.empty() ? 0 : cv::countNonZero(m); }
int Differ(const cv::Mat& a, const cv::Mat& b) { return cv::countNonZero(a != b); }

// At scale 1 the frame's mask is exactly the propagator followed by the planes and the growth,
// as slam::System composed them before the work scale existed.
TEST(FrameMask, ScaleOneIsThePropagatorAndTheCompletionAtFullSize) {
  const Scene scene;
  FrameMask masks(TestCamera(), Options(1));
  MaskPropagator propagator(TestCamera(), MaskPropagationOptions{});
  const geometry::SE3 motion(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.02, 0.0, 0.0));
  for (int frame = 0; frame < 3; ++frame) {
    const cv::Mat network = frame == 1 ? cv::Mat() : scene.network;  // frame 1: missed
    const cv::Mat got = masks.MaskFor(
        network, scene.depth, network.empty() ? scene.depth.size() : network.size(), motion);
    cv::Mat expected = propagator.MaskFor(network, scene.depth.size(), motion, scene.depth);
    const auto planes = feature::StructurePlanes::Find(scene.depth, TestCamera(), expected,
                                                       feature::StructurePlaneOptions{});
    feature::MaskCompletionOptions completion;
    completion.max_grow_px = FrameMaskOptions{}.completion_px;
    expected = feature::CompleteMaskByDepth(expected, scene.depth, completion, &planes);
    ASSERT_EQ(got.size(), expected.size());
    EXPECT_EQ(Differ(got, expected), 0) << "frame " << frame;
    masks.Commit();
    propagator.Commit(scene.depth);
  }
}

// At scale 2 the mask covers the network's pixels exactly, completes the missed legs as at full
// size without entering the floor, and differs from the full-size mask only along its edges.
TEST(FrameMask, HalfScaleKeepsTheNetworksPixelsAndCompletesTheBody) {
  const Scene scene;
  FrameMask half(TestCamera(), Options(2)), full(TestCamera(), Options(1));
  const cv::Mat h = half.MaskFor(scene.network, scene.depth, scene.depth.size(), std::nullopt);
  const cv::Mat f = full.MaskFor(scene.network, scene.depth, scene.depth.size(), std::nullopt);
  ASSERT_EQ(h.size(), scene.depth.size());
  EXPECT_EQ(cv::countNonZero(scene.network & ~h), 0);  // every network pixel kept
  const int body = Count(scene.body);
  EXPECT_GT(Count(h & scene.body), 0.99 * body);   // the legs completed
  EXPECT_LT(Count(h & ~scene.body), 0.01 * body);  // not the floor, not the wall
  // Against full size: the pixels that differ lie within 2 px of the full-size mask's edge.
  cv::Mat edge_band;
  cv::morphologyEx(f, edge_band, cv::MORPH_GRADIENT,
                   cv::getStructuringElement(cv::MORPH_RECT, cv::Size(5, 5)));
  EXPECT_EQ(cv::countNonZero((h != f) & ~edge_band), 0);
}

// A missed frame gets the carried mask at either scale, on the moved body within 2 px.
TEST(FrameMask, HalfScaleCarriesTheMaskWithTheMotion) {
  const Scene scene;
  FrameMaskOptions options = Options(2);
  options.completion_px = 0;  // the carrying alone
  FrameMask masks(TestCamera(), options);
  masks.MaskFor(scene.network, scene.depth, scene.depth.size(), std::nullopt);
  masks.Commit();
  // The camera moved 0.08 m to the right: the body (2 m) moves 20 px left, the carried mask
  // grows 2 px a frame.
  const geometry::SE3 T_cur_last(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-0.08, 0.0, 0.0));
  // The new frame's depth has the body there too (what lies around it does not matter here).
  cv::Mat moved = Scene().depth;
  moved(cv::Rect(230, 60, 160, 340)).setTo(2.0f);
  const cv::Mat carried = masks.MaskFor(cv::Mat(), moved, moved.size(), T_cur_last);
  ASSERT_FALSE(carried.empty());
  const cv::Rect box = cv::boundingRect(carried);
  EXPECT_NEAR(box.x, 230 - 2, 2);
  EXPECT_NEAR(box.width, 160 + 4, 4);
  EXPECT_NEAR(box.y, 60 - 2, 2);
}

TEST(FrameMask, RegionsAreCarriedAndNothingMovableGivesNoMask) {
  const Scene scene;
  FrameMask masks(TestCamera(), Options(2));
  EXPECT_TRUE(masks.MaskFor(cv::Mat(), scene.depth, scene.depth.size(), std::nullopt).empty());
  cv::Mat region = cv::Mat::zeros(480, 640, CV_8UC1);
  region(cv::Rect(51, 51, 3, 3)).setTo(255);  // odd place and size: pooled into 2x2 blocks
  masks.AddRegion(region);
  masks.Commit();
  const cv::Mat next = masks.MaskFor(cv::Mat(), cv::Mat(), scene.depth.size(), geometry::SE3());
  ASSERT_FALSE(next.empty());
  EXPECT_EQ(cv::countNonZero(region & ~next), 0);
}

TEST(FrameMask, OptionsAreChecked) {
  for (const int scale : {0, 5}) {
    EXPECT_THROW(FrameMask(TestCamera(), Options(scale)), InputError) << scale;
  }
  FrameMaskOptions options;
  options.completion_px = -1;
  EXPECT_THROW(FrameMask(TestCamera(), options), InputError);
}

}  // namespace
}  // namespace moslam::slam
