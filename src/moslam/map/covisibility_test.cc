// Covisibility bookkeeping: edge weights count shared points, the spanning tree parent is the most
// covisible earlier keyframe, and erasing a keyframe reconnects its children and frees its points.
#include <cmath>
#include <memory>

#include <gtest/gtest.h>

#include "moslam/map/keyframe_graph.h"
#include "moslam/map/map.h"

namespace moslam::map {
namespace {

feature::Frame MakeFrame(int n) {
  feature::Frame f;
  f.keypoints.resize(n);
  f.keypoints_undistorted.resize(n);
  f.descriptors = cv::Mat::zeros(n, 32, CV_8U);
  // Stereo observations (ORB-SLAM2 counts them twice when deciding to erase a point).
  f.u_right.assign(n, 100.0f);
  f.depth.assign(n, 5.0f);
  f.scale_factors = {1.0f, 1.2f};
  f.inv_scale_factors = {1.0f, 1.0f / 1.2f};
  f.level_sigma2 = {1.0f, 1.44f};
  f.inv_level_sigma2 = {1.0f, 1.0f / 1.44f};
  return f;
}

// Creates `n` points observed by every keyframe in `kfs` at indices [first, first + n).
void SharePoints(Map* map, const std::vector<std::shared_ptr<KeyFrame>>& kfs, int first, int n) {
  for (int i = first; i < first + n; ++i) {
    auto p = map->CreateMapPoint(Eigen::Vector3d(0, 0, 5), kfs.front());
    for (const auto& kf : kfs) {
      kf->points[i] = p;
      p->AddObservation(kf, i);
    }
  }
}

TEST(Covisibility, WeightsCountSharedPointsAndParentIsMostCovisible) {
  Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto k0 = map.CreateKeyFrame(MakeFrame(100), geometry::SE3());
  auto k1 = map.CreateKeyFrame(MakeFrame(100), geometry::SE3());
  auto k2 = map.CreateKeyFrame(MakeFrame(100), geometry::SE3());
  SharePoints(&map, {k0, k1, k2}, 0, 20);
  SharePoints(&map, {k1, k2}, 20, 30);
  SharePoints(&map, {k0, k2}, 50, 5);
  k0->UpdateConnections();
  k1->UpdateConnections();
  k2->UpdateConnections();
  EXPECT_EQ(k2->Weight(k1->id), 50);
  EXPECT_EQ(k2->Weight(k0->id), 25);
  EXPECT_EQ(k1->Weight(k2->id), 50);  // the other side of the edge is updated
  EXPECT_EQ(k0->Weight(k2->id), 25);
  const auto best = k2->BestCovisibles(-1);
  ASSERT_EQ(best.size(), 2u);
  EXPECT_EQ(best[0]->id, k1->id);
  EXPECT_EQ(best[1]->id, k0->id);
  EXPECT_EQ(k2->parent(), k1);
  EXPECT_EQ(k1->parent(), k0);  // k1's only covisible keyframe at its first update
  EXPECT_EQ(k0->parent(), nullptr);
  EXPECT_EQ(k1->children().count(k2->id), 1u);
}

TEST(Covisibility, EraseKeyFrameReconnectsChildrenAndDropsOrphans) {
  Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto k0 = map.CreateKeyFrame(MakeFrame(100), geometry::SE3());
  auto k1 = map.CreateKeyFrame(MakeFrame(100), geometry::SE3());
  auto k2 = map.CreateKeyFrame(MakeFrame(100), geometry::SE3());
  SharePoints(&map, {k0, k1, k2}, 0, 20);
  SharePoints(&map, {k1, k2}, 20, 30);
  for (auto& kf : {k0, k1, k2}) kf->UpdateConnections();
  ASSERT_EQ(map.points().size(), 50u);
  EXPECT_EQ(map.num_keyframes(), 3u);  // the counts read without the lock follow every change
  EXPECT_EQ(map.num_points(), 50u);
  map.EraseKeyFrame(k1);
  EXPECT_EQ(map.num_keyframes(), 2u);
  EXPECT_TRUE(k1->bad());
  EXPECT_EQ(map.keyframes().count(k1->id), 0u);
  EXPECT_EQ(k2->parent(), k0);
  EXPECT_EQ(k2->Weight(k1->id), 0);
  // The 30 points seen only by k1 and k2 (monocular: 1 observation left) are erased.
  EXPECT_EQ(map.points().size(), 20u);
  EXPECT_EQ(map.num_points(), 20u);
  for (int i = 20; i < 50; ++i) EXPECT_EQ(k2->points[i], nullptr);
  // The first keyframe is never erased.
  map.EraseKeyFrame(k0);
  EXPECT_FALSE(k0->bad());
}

TEST(Covisibility, ReplaceMovesObservations) {
  Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto k0 = map.CreateKeyFrame(MakeFrame(10), geometry::SE3());
  auto k1 = map.CreateKeyFrame(MakeFrame(10), geometry::SE3());
  auto a = map.CreateMapPoint(Eigen::Vector3d(0, 0, 1), k0);
  auto b = map.CreateMapPoint(Eigen::Vector3d(0, 0, 1), k1);
  k0->points[3] = a;
  a->AddObservation(k0, 3);
  k1->points[4] = b;
  b->AddObservation(k1, 4);
  map.Replace(a, b);
  EXPECT_TRUE(a->bad);
  EXPECT_EQ(a->replaced_by.lock(), b);
  EXPECT_EQ(k0->points[3], b);
  EXPECT_EQ(b->IndexIn(k0->id), 3);
  EXPECT_EQ(b->num_observations(), 4);  // two stereo observations
  EXPECT_EQ(map.points().count(a->id), 0u);
  EXPECT_EQ(map.num_points(), 1u);
}

TEST(MapPoint, DescriptorIsTheMedoidAndScaleRangeFollowsTheReference) {
  Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (int k = 0; k < 3; ++k) {
    feature::Frame f = MakeFrame(1);
    f.keypoints_undistorted[0].octave = 1;
    // Descriptors 0xff.., 0x01.., 0x03..: the least median distance is not the first one.
    f.descriptors.setTo(cv::Scalar(k == 0 ? 0xff : (k == 1 ? 0x01 : 0x03)));
    kfs.push_back(map.CreateKeyFrame(
        f, geometry::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-k * 1.0, 0, 0))));
  }
  auto p = map.CreateMapPoint(Eigen::Vector3d(0, 0, 4), kfs[0]);
  for (const auto& kf : kfs) {
    kf->points[0] = p;
    p->AddObservation(kf, 0);
  }
  p->ComputeDistinctiveDescriptor();
  EXPECT_EQ(p->descriptor.at<uint8_t>(0, 0), 0x01);
  p->UpdateNormalAndDepth();
  EXPECT_NEAR(p->max_distance, 4.0 * 1.2, 1e-5);  // reference distance times its level's scale
  EXPECT_NEAR(p->min_distance, 4.0, 1e-5);        // divided by the top level's scale (1.2)
  EXPECT_GT(p->normal.z(), 0.8);
  EXPECT_EQ(p->PredictScale(4.0f * 1.2f, std::log(1.2f), 2), 0);
  EXPECT_EQ(p->PredictScale(4.0f, std::log(1.2f), 2), 1);
}

// The graph a viewer draws: edges by index into the good keyframes, so an erased keyframe shifts
// the later indices and takes its edges along; covisibility only as heavy as asked, both ways.
TEST(KeyFrameGraph, IndexesTheGoodKeyFramesAndKeepsHeavyEdgesAndLoops) {
  Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  std::vector<std::shared_ptr<KeyFrame>> kfs;
  for (int k = 0; k < 4; ++k) kfs.push_back(map.CreateKeyFrame(MakeFrame(300), geometry::SE3()));
  SharePoints(&map, {kfs[0], kfs[1]}, 0, 120);
  SharePoints(&map, {kfs[1], kfs[2]}, 120, 50);  // k2 only through k1: erased below
  SharePoints(&map, {kfs[1], kfs[3]}, 170, 110);
  SharePoints(&map, {kfs[0], kfs[3]}, 280, 10);  // too light to draw
  for (auto& kf : kfs) kf->UpdateConnections();
  map.EraseKeyFrame(kfs[2]);
  map.AddLoopEdge(kfs[3]->id, kfs[0]->id);

  const IndexedKeyFrameGraph light = IndexKeyFrameGraph(map, /*with_graph=*/false, 100);
  EXPECT_EQ(light.ids, (std::vector<uint64_t>{kfs[0]->id, kfs[1]->id, kfs[3]->id}));
  EXPECT_EQ(light.poses.size(), 3u);
  EXPECT_EQ(light.loops, (std::vector<uint32_t>{0, 2}));  // loop keyframe first, then current
  EXPECT_TRUE(light.covisibility.empty());
  EXPECT_TRUE(light.spanning_tree.empty());

  const IndexedKeyFrameGraph graph = IndexKeyFrameGraph(map, /*with_graph=*/true, 100);
  EXPECT_EQ(graph.loops, light.loops);
  EXPECT_EQ(graph.covisibility,
            (std::vector<uint32_t>{0, 1, 120, 1, 0, 120, 1, 2, 110, 2, 1, 110}));
  EXPECT_EQ(graph.spanning_tree, (std::vector<uint32_t>{1, 0, 2, 1}));
}

}  // namespace
}  // namespace moslam::map
