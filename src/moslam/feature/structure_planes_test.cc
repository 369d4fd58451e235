#include "moslam/feature/structure_planes.h"

#include <cmath>

#include <gtest/gtest.h>

#include "moslam/feature/movable_mask.h"
#include "moslam/feature/test_images.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

// A room seen from 1.2 m above its floor (camera looking along +z, y down): the floor (y = 1.2),
// a wall at z = 5 and a "person", a box face 0.6 m wide standing on the floor 3 m away, from
// 1.6 m above the floor down to it. The person's feet touch the floor: at the box's lowest row
// floor and box have the same depth, so the floor is depth-connected to the body.
struct Room {
  cv::Mat depth, body;
};
Room RenderRoom() {
  const auto cam = test::TestCamera();
  Room room{cv::Mat(480, 640, CV_32FC1), cv::Mat::zeros(480, 640, CV_8UC1)};
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const double x = (u - cam.cx()) / cam.fx(), y = (v - cam.cy()) / cam.fy();
      double z = 5.0;                         // the wall
      if (y > 0.0) z = std::min(z, 1.2 / y);  // the floor
      const bool body = std::abs(3.0 * x) <= 0.3 && 3.0 * y >= -0.4 && 3.0 * y <= 1.2;
      if (body) {
        z = 3.0;
        room.body.at<uint8_t>(v, u) = 255;
      }
      room.depth.at<float>(v, u) = static_cast<float>(z);
    }
  }
  return room;
}

bool OnFloor(int v) { return (v - test::TestCamera().cy()) / test::TestCamera().fy() > 0.0; }

TEST(StructurePlanes, FindsFloorAndWallButNotTheBody) {
  const Room room = RenderRoom();
  const auto planes =
      StructurePlanes::Find(room.depth, test::TestCamera(), cv::Mat(), StructurePlaneOptions{});
  ASSERT_EQ(planes.size(), 2);
  // One plane is the floor (normal along y), one the wall (normal along z).
  int floor = 0, wall = 0;
  for (int i = 0; i < planes.size(); ++i) {
    const Eigen::Vector4d& p = planes.plane(i);
    if (std::abs(p.y()) > 0.99 && std::abs(std::abs(p[3]) - 1.2) < 0.01) ++floor;
    if (std::abs(p.z()) > 0.99 && std::abs(std::abs(p[3]) - 5.0) < 0.01) ++wall;
  }
  EXPECT_EQ(floor, 1);
  EXPECT_EQ(wall, 1);
  int body_on_structure = 0, floor_pixels = 0, floor_on_structure = 0;
  for (int v = 0; v < 480; ++v) {
    for (int u = 0; u < 640; ++u) {
      const float z = room.depth.at<float>(v, u);
      const bool structure = planes.Contains(u, v, z);
      if (room.body.at<uint8_t>(v, u) != 0) {
        body_on_structure += structure;
      } else if (OnFloor(v) && z < 4.9f) {
        ++floor_pixels;
        floor_on_structure += structure;
      }
    }
  }
  // Only the body's lowest rows, within the inlier distance of the floor (0.02 + 0.01 * 3 m, 8
  // rows at 3 m), lie on structure: its feet.
  const int width = cv::boundingRect(room.body).width;
  EXPECT_LE(body_on_structure, 10 * width);
  EXPECT_GE(floor_on_structure, 0.98 * floor_pixels);
  // Deterministic.
  const auto again =
      StructurePlanes::Find(room.depth, test::TestCamera(), cv::Mat(), StructurePlaneOptions{});
  ASSERT_EQ(again.size(), planes.size());
  for (int i = 0; i < planes.size(); ++i) EXPECT_EQ(again.plane(i), planes.plane(i));
}

TEST(StructurePlanes, AFlatBodyIsNeverStructure) {
  // Seen from 0.8 m, the body's face fills a third of the image: a large share of the samples,
  // but 0.6 m across, under min_side_m.
  const auto cam = test::TestCamera();
  cv::Mat depth(480, 640, CV_32FC1, cv::Scalar(5.0f));
  depth(cv::Rect(320 - 187, 0, 375, 480)).setTo(0.8f);
  const auto planes = StructurePlanes::Find(depth, cam, cv::Mat(), StructurePlaneOptions{});
  EXPECT_FALSE(planes.Contains(320, 240, 0.8f));
  EXPECT_TRUE(planes.Contains(20, 240, 5.0f));
  // Excluded (masked) pixels are not sampled: with the wall masked there is nothing left.
  cv::Mat exclude(480, 640, CV_8UC1, cv::Scalar(255));
  EXPECT_EQ(StructurePlanes::Find(depth, cam, exclude, StructurePlaneOptions{}).size(), 0);
}

TEST(CompleteMaskByDepth, CompletesABodyFromItsHeadWithoutRunningAlongTheFloor) {
  const Room room = RenderRoom();
  // The network saw the head only: the body's top 15 %.
  cv::Mat head = room.body.clone();
  const cv::Rect box = cv::boundingRect(room.body);
  head(cv::Rect(box.x, box.y + box.height * 15 / 100, box.width, box.height * 85 / 100)).setTo(0);
  MaskCompletionOptions options;
  options.max_grow_px = 400;
  const auto planes =
      StructurePlanes::Find(room.depth, test::TestCamera(), head, StructurePlaneOptions{});
  const cv::Mat with = CompleteMaskByDepth(head, room.depth, options, &planes);
  const cv::Mat without = CompleteMaskByDepth(head, room.depth, options);
  const auto count = [&](const cv::Mat& m, bool on_body) {
    cv::Mat region = on_body ? room.body : ~room.body, both;
    cv::bitwise_and(m, region, both);
    return cv::countNonZero(both);
  };
  const int body = cv::countNonZero(room.body);
  // The whole body but its feet (the 8 rows within the floor plane's inlier distance) ...
  EXPECT_GE(count(with, true), body - 12 * box.width);
  // ... and nearly nothing else: no floor.
  EXPECT_LE(count(with, false), 0.01 * body);
  // Without the planes the growth runs along the floor through the feet.
  EXPECT_GE(count(without, true), 0.97 * body);
  EXPECT_GE(count(without, false), 0.5 * body);
}

TEST(StructurePlanes, OptionsAreChecked) {
  StructurePlaneOptions o;
  o.grid_px = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = StructurePlaneOptions{};
  o.min_share = 1.5;
  EXPECT_THROW(o.Check(), InputError);
  o = StructurePlaneOptions{};
  o.inlier_abs = o.inlier_rel = 0.0;
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace moslam::feature
