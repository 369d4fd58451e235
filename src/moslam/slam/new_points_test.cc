// Triangulation of new map points between two keyframes with exact synthetic observations.
#include "moslam/slam/new_points.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "moslam/slam/test_scene.h"

namespace moslam::slam {
namespace {

TEST(CreateNewMapPoints, TriangulatesUnmatchedKeypointsExactly) {
  const testing::Scene scene = testing::RandomScene(120, 3);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  auto kf2 = testing::ObserveScene(&map, scene, testing::CameraAt(1.0));
  // 30 points already mapped make the two keyframes covisible.
  testing::AddSharedPoints(&map, scene, {kf1, kf2}, 0, 30);
  kf1->UpdateConnections();
  kf2->UpdateConnections();
  ASSERT_EQ(kf2->BestCovisibles(-1).size(), 1u);

  const auto created = CreateNewMapPoints(&map, kf2, testing::TestCamera());
  int inside_both = 0;
  for (size_t i = 30; i < scene.points.size(); ++i) {
    const auto& kp1 = kf1->frame.keypoints[i].pt;
    const auto& kp2 = kf2->frame.keypoints[i].pt;
    if (kp1.x >= 0 && kp1.x < 640 && kp1.y >= 0 && kp1.y < 480 && kp2.x >= 0 && kp2.x < 640 &&
        kp2.y >= 0 && kp2.y < 480) {
      ++inside_both;
    }
  }
  EXPECT_GE(static_cast<int>(created.size()), inside_both * 9 / 10);
  for (const auto& p : created) {
    const int i = p->IndexIn(kf2->id);
    ASSERT_GE(i, 30);
    EXPECT_EQ(p->IndexIn(kf1->id), i);  // the right keypoint pair
    EXPECT_LT((p->position - scene.points[i]).norm(), 1e-3 * scene.points[i].z());
    EXPECT_EQ(kf1->points[i], p);
    EXPECT_EQ(p->num_observations(), 2);
    EXPECT_GT(p->max_distance, p->min_distance);
  }
  EXPECT_EQ(map.points().size(), 30u + created.size());
}

TEST(CreateNewMapPoints, NoNeighboursNoPoints) {
  const testing::Scene scene = testing::RandomScene(50, 4);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  EXPECT_TRUE(CreateNewMapPoints(&map, kf, testing::TestCamera()).empty());
}

TEST(SearchForTriangulation, RejectsMatchesOffTheEpipolarLine) {
  const testing::Scene scene = testing::RandomScene(80, 5);
  map::Map map;
  std::lock_guard<std::mutex> lock(map.mutex());
  auto kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
  // kf2 sees the same descriptors 1 m higher up: 50-100 px off the (horizontal) epipolar lines.
  testing::Scene moved = scene;
  for (auto& p : moved.points) p.y() += 1.0;
  auto kf2 = testing::ObserveScene(&map, moved, testing::CameraAt(1.0));
  EXPECT_TRUE(SearchForTriangulation(*kf1, *kf2, testing::TestCamera()).empty());
}

// Two keyframes of a random scene 1 m apart, copies of their frames made monocular, and the
// search between those copies (with or without direct indices).
struct MonocularPair {
  MonocularPair(int points, uint32_t seed) : scene(testing::RandomScene(points, seed)) {
    std::lock_guard<std::mutex> lock(map.mutex());
    kf1 = testing::ObserveScene(&map, scene, testing::CameraAt(0.0));
    kf2 = testing::ObserveScene(&map, scene, testing::CameraAt(1.0));
    f1 = kf1->frame;
    f2 = kf2->frame;
    f1.bf = f2.bf = 0.0;
    free1.assign(f1.size(), true);
    free2.assign(f2.size(), true);
  }
  std::vector<std::pair<size_t, size_t>> Search(const vocab::FeatureVector* fv1,
                                                const vocab::FeatureVector* fv2) const {
    return SearchForTriangulation(f1, kf1->T_cam_world(), free1, f2, kf2->T_cam_world(), free2,
                                  testing::TestCamera(), fv1, fv2);
  }
  testing::Scene scene;
  map::Map map;
  std::shared_ptr<map::KeyFrame> kf1, kf2;
  feature::Frame f1, f2;
  std::vector<bool> free1, free2;
};

// Monocular pairs with a bag-of-words direct index compare only keypoints under the same
// vocabulary node (ORB-SLAM2): with every keypoint under one node the result is the brute-force
// one, with nodes that keep each true pair together too, and nothing matches across nodes.
TEST(SearchForTriangulation, MonocularPairsSearchWithinVocabularyNodes) {
  const MonocularPair pair(120, 6);
  const feature::Frame &f1 = pair.f1, &f2 = pair.f2;
  const auto search = [&](const vocab::FeatureVector* fv1, const vocab::FeatureVector* fv2) {
    return pair.Search(fv1, fv2);
  };
  const auto brute = search(nullptr, nullptr);
  ASSERT_GT(brute.size(), 60u);
  for (const auto& [i1, i2] : brute) ASSERT_EQ(i1, i2);  // exact synthetic descriptors

  const auto by_parity = [](size_t n, uint32_t even_node, uint32_t odd_node) {
    vocab::FeatureVector fv;
    for (uint32_t i = 0; i < n; ++i) fv[i % 2 == 0 ? even_node : odd_node].push_back(i);
    return fv;
  };
  const vocab::FeatureVector one1 = by_parity(f1.size(), 7, 7), one2 = by_parity(f2.size(), 7, 7);
  EXPECT_EQ(search(&one1, &one2), brute);
  const vocab::FeatureVector split1 = by_parity(f1.size(), 3, 5);
  const vocab::FeatureVector split2 = by_parity(f2.size(), 3, 5);
  auto split = search(&split1, &split2);  // node by node: the same pairs in another order
  std::sort(split.begin(), split.end());
  EXPECT_EQ(split, brute);
  const vocab::FeatureVector swapped2 = by_parity(f2.size(), 5, 3);
  EXPECT_TRUE(search(&split1, &swapped2).empty());
}

// The epipolar band is 3.84 sigma^2 (chi-square, 1 DoF, 95 %) at the keypoint's pyramid level:
// with the cameras 1 m apart along x the epipolar lines are the image rows, so a keypoint moved
// off its row by 0.9 of the band's half width sqrt(3.84) * 1.2^octave still matches and one moved
// by 1.1 of it does not, at every level.
TEST(SearchForTriangulation, BandHalfWidthFollowsThePyramidLevel) {
  MonocularPair pair(240, 10);
  auto& kps = pair.f2.keypoints_undistorted;
  for (size_t i = 0; i < kps.size(); ++i) {
    kps[i].octave = static_cast<int>(i % 8);
    const float half_width = std::sqrt(3.84f * pair.f2.level_sigma2[kps[i].octave]);
    kps[i].pt.y += (i % 16 < 8 ? 0.9f : 1.1f) * half_width * (i % 2 == 0 ? 1.0f : -1.0f);
  }
  std::vector<bool> matched(kps.size(), false);
  for (const auto& [i1, i2] : pair.Search(nullptr, nullptr)) {
    ASSERT_EQ(i1, i2);
    matched[i2] = true;
  }
  int inside = 0, inside_matched = 0;
  for (size_t i = 0; i < kps.size(); ++i) {
    if (i % 16 < 8) {
      ++inside;
      inside_matched += matched[i];
    } else {
      EXPECT_FALSE(matched[i]) << "keypoint " << i << " at octave " << kps[i].octave;
    }
  }
  // Keypoints outside frame1's image have no partner.
  EXPECT_GT(inside_matched, inside * 8 / 10);
}

// The search over every keypoint (stereo / RGB-D pairs; monocular ones without a direct index)
// and the search within direct-index nodes take their band candidates two ways (the whole frame,
// or a node's list); with every keypoint in one node the two must give the same matches in the
// same order (ties in descriptor distance go to the first): on keypoints moved 0-4 px off their
// lines at every pyramid level (band half widths 2-7 px, so many sit at its edge), with
// descriptors repeated so that ties occur. The band's width itself: the test above.
TEST(SearchForTriangulation, BandPrefilterKeepsTheSameMatches) {
  MonocularPair pair(400, 8);
  feature::Frame &f1 = pair.f1, &f2 = pair.f2;
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> offset(-4.0f, 4.0f);
  std::uniform_int_distribution<int> octave(0, 7);
  for (feature::Frame* f : {&f1, &f2}) {
    for (auto& kp : f->keypoints_undistorted) {
      kp.pt += cv::Point2f(offset(rng), offset(rng));
      kp.octave = octave(rng);
    }
  }
  for (int i = 0; i + 1 < f2.descriptors.rows; i += 3) {  // a third of frame2's descriptors twice
    f2.descriptors.row(i).copyTo(f2.descriptors.row(i + 1));
  }
  for (size_t i = 0; i < pair.free2.size(); i += 7) pair.free2[i] = false;
  vocab::FeatureVector one1, one2;
  for (uint32_t i = 0; i < f1.size(); ++i) one1[0].push_back(i);
  for (uint32_t i = 0; i < f2.size(); ++i) one2[0].push_back(i);
  const auto one_by_one = pair.Search(&one1, &one2);
  ASSERT_GT(one_by_one.size(), 100u);
  EXPECT_EQ(pair.Search(nullptr, nullptr), one_by_one);
}

}  // namespace
}  // namespace moslam::slam
