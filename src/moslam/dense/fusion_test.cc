#include "moslam/dense/fusion.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>

#include "moslam/dense/cloud.h"
#include "moslam/dense/evaluation.h"
#include "moslam/dense/stereo_depth.h"
#include "moslam/util/error.h"

namespace moslam::dense {
namespace {

const Intrinsics kCamera{300.0, 300.0, 160.0, 120.0};

// A camera at the origin looking along +z at a wall 2 m away; with `person`, a 1 m-deep block in
// the middle of the image (columns 120..199, rows 80..159) stands in front of it, and `mask`
// covers exactly that block.
DepthView WallView(bool person, bool masked) {
  DepthView view;
  view.depth = cv::Mat(240, 320, CV_32FC1, cv::Scalar(2.0f));
  view.colour = cv::Mat(240, 320, CV_8UC3, cv::Scalar(200, 100, 50));
  const cv::Rect block(120, 80, 80, 80);
  if (person) view.depth(block).setTo(1.0f);
  if (masked) {
    view.mask = cv::Mat::zeros(240, 320, CV_8UC1);
    view.mask(block).setTo(255);
  }
  return view;
}

// Occupied voxels whose centre is nearer than 1.5 m (the person's) and farther (the wall's).
std::pair<int, int> CountByDepth(const DenseFusion& fusion) {
  int near = 0, far = 0;
  for (const Voxel& v : fusion.OccupiedVoxels()) (v.centre.z() < 1.5f ? near : far) += 1;
  return {near, far};
}

TEST(DenseFusion, MaskedPixelsLeaveNoTrace) {
  DenseFusion masked(kCamera), unmasked(kCamera);
  masked.Insert(WallView(true, true));
  unmasked.Insert(WallView(true, false));
  const auto [near_masked, far_masked] = CountByDepth(masked);
  const auto [near_unmasked, far_unmasked] = CountByDepth(unmasked);
  EXPECT_EQ(near_masked, 0);
  // The 80x80-pixel block at 1 m spans 0.27 m: a face of about 6x6 voxels.
  EXPECT_GT(near_unmasked, 20);
  EXPECT_GT(far_masked, 500);  // the wall around it
  // The wall behind the masked block was never seen: the masked fusion holds no more wall than
  // the unmasked one, whose rays stop at the person.
  EXPECT_LE(far_masked, far_unmasked + 5);
}

TEST(DenseFusion, LaterRaysClearWhereSomeoneStood) {
  // Seen once unmasked, then three times with the person gone: the rays to the wall pass where
  // the person was and clear it (OctoMap's hit 0.7 / miss 0.4: one hit, then two misses bring
  // the voxel back below 0.5).
  DenseFusion fusion(kCamera);
  fusion.Insert(WallView(true, false));
  ASSERT_GT(CountByDepth(fusion).first, 0);
  for (int i = 0; i < 3; ++i) fusion.Insert(WallView(false, false));
  EXPECT_EQ(CountByDepth(fusion).first, 0);
  DenseFusionOptions endpoints_only;
  endpoints_only.ray_casting = false;
  DenseFusion kept(kCamera, endpoints_only);
  kept.Insert(WallView(true, false));
  for (int i = 0; i < 3; ++i) kept.Insert(WallView(false, false));
  EXPECT_GT(CountByDepth(kept).first, 0);  // without rays the trail stays
}

TEST(DenseFusion, BackProjectPlacesPixelsAtTheirDepthAndPose) {
  DepthView view = WallView(true, true);
  view.T_world_cam = geometry::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(1.0, 0.0, 0.0));
  DenseFusionOptions options;
  options.pixel_step = 1;
  InsertStats stats;
  const auto inside = BackProject(kCamera, options, view, MaskUse::kOnly, nullptr, &stats);
  EXPECT_EQ(inside.size(), 80u * 80u);
  for (const Eigen::Vector3d& p : inside) EXPECT_NEAR(p.z(), 1.0, 1e-9);
  // The pixel (160, 120) is the principal point: straight ahead, shifted by the pose.
  const auto outside = BackProject(kCamera, options, view, MaskUse::kLeaveOut, nullptr, &stats);
  // The mask grown by 4 px (an elliptic kernel: rounded corners) leaves out up to an 88x88 block.
  EXPECT_GT(stats.masked, 80u * 80u);
  EXPECT_LE(stats.masked, 88u * 88u);
  EXPECT_EQ(outside.size() + stats.masked, 320u * 240u);
  for (const Eigen::Vector3d& p : outside) {
    EXPECT_NEAR(p.z(), 2.0, 1e-9);
    EXPECT_GE(p.x(), 1.0 - 160.0 * 2.0 / 300.0 - 1e-9);
  }
}

TEST(DenseFusion, BadInputsAreInputErrors) {
  DenseFusionOptions bad;
  bad.resolution = 0.0;
  EXPECT_THROW(DenseFusion(kCamera, bad), InputError);
  bad = {};
  bad.max_depth = bad.min_depth;
  EXPECT_THROW(bad.Check(), InputError);
  DenseFusion fusion(kCamera);
  DepthView view = WallView(false, false);
  view.mask = cv::Mat::zeros(10, 10, CV_8UC1);
  EXPECT_THROW(fusion.Insert(view), InputError);
  view = WallView(false, false);
  view.depth.convertTo(view.depth, CV_16U);
  EXPECT_THROW(fusion.Insert(view), InputError);
  EXPECT_THROW(DenseFusion(Intrinsics{}, {}), InputError);
}

TEST(DenseCloud, PlyHasOneVertexPerVoxelAndThePictureShowsThem) {
  DenseFusion fusion(kCamera);
  fusion.Insert(WallView(true, false));
  const std::vector<Voxel> voxels = fusion.OccupiedVoxels();
  ASSERT_EQ(voxels.size(), fusion.NumOccupied());
  const std::string ply = PlyBytes(voxels);
  const std::string header_end = "end_header\n";
  const size_t body = ply.find(header_end) + header_end.size();
  EXPECT_NE(ply.find("element vertex " + std::to_string(voxels.size()) + "\n"), std::string::npos);
  EXPECT_EQ(ply.size() - body, voxels.size() * 15);
  // Colour averaged per voxel (OctoMap's integer running mean loses a little): the view's BGR
  // (200, 100, 50) is RGB (50, 100, 200).
  EXPECT_NEAR(voxels.front().r, 50, 3);
  EXPECT_NEAR(voxels.front().b, 200, 3);
  const cv::Mat picture = RenderTopView(voxels, 0.05);
  ASSERT_FALSE(picture.empty());
  cv::Mat grey;
  cv::extractChannel(picture, grey, 0);
  EXPECT_GT(cv::countNonZero(grey < 250), 100);
}

TEST(DenseEvaluation, ScoresCountPeopleVoxelsAndStaticCompleteness) {
  VoxelSet people(0.05), statics(0.05);
  people.Add(Eigen::Vector3d(0.01, 0.01, 0.01));  // voxel (0, 0, 0)
  people.Add(Eigen::Vector3d(1.01, 0.01, 0.01));  // voxel (20, 0, 0), also static
  statics.Add(Eigen::Vector3d(1.02, 0.02, 0.02));
  statics.Add(Eigen::Vector3d(2.01, 0.01, 0.01));  // voxel (40, 0, 0): seen, not in the map
  statics.Add(Eigen::Vector3d(3.01, 0.01, 0.01));  // voxel (60, 0, 0): a neighbour is in the map
  std::vector<Voxel> map(3);
  map[0].centre = Eigen::Vector3f(0.025f, 0.025f, 0.025f);
  map[1].centre = Eigen::Vector3f(1.025f, 0.025f, 0.025f);
  map[2].centre = Eigen::Vector3f(3.075f, 0.025f, 0.025f);
  const DenseMapScores s = ScoreDenseMap(map, people, statics);
  EXPECT_EQ(s.occupied, 3u);
  EXPECT_EQ(s.in_people, 1u);  // the foot on the floor counts as static
  EXPECT_EQ(s.static_seen, 3u);
  EXPECT_EQ(s.static_occupied, 1u);
  EXPECT_EQ(s.static_occupied_near, 2u);
  EXPECT_NEAR(s.people_fraction, 1.0 / 3.0, 1e-12);
  EXPECT_TRUE(people.Contains(Eigen::Vector3d(-0.0, 0.049, 0.0)));
  EXPECT_FALSE(people.Contains(Eigen::Vector3d(-0.001, 0.0, 0.0)));  // voxel (-1, 0, 0)
}

TEST(DenseStereo, DisparityOfAShiftedTextureGivesItsDepth) {
  // A random texture and the same texture 20 px to the left: every matched pixel has disparity
  // 20, so depth bf / 20.
  cv::Mat left(120, 240, CV_8UC1);
  cv::RNG rng(7);
  rng.fill(left, cv::RNG::UNIFORM, 0, 255);
  cv::Mat right = cv::Mat::zeros(left.size(), CV_8UC1);
  left(cv::Rect(20, 0, 220, 120)).copyTo(right(cv::Rect(0, 0, 220, 120)));
  const double bf = 40.0;
  const cv::Mat depth = DepthFromStereo(left, right, bf);
  int good = 0, valid = 0;
  for (int v = 10; v < 110; ++v) {
    for (int u = 150; u < 230; ++u) {
      const float z = depth.at<float>(v, u);
      if (z <= 0.0f) continue;
      ++valid;
      good += std::abs(z - 2.0f) < 0.02f ? 1 : 0;
    }
  }
  EXPECT_GT(valid, 6000);
  EXPECT_GT(good, 0.95 * valid);
  EXPECT_THROW(DepthFromStereo(left, right(cv::Rect(0, 0, 100, 100)), bf), InputError);
  StereoDepthOptions bad;
  bad.num_disparities = 100;
  EXPECT_THROW(bad.Check(), InputError);
}

}  // namespace
}  // namespace moslam::dense
