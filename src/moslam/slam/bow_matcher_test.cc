// BoW matching on synthetic keyframes (slam/test_scene.h): random descriptors, direct indexes
// built by hand, so that which features may be compared (same node) is known exactly.
#include "moslam/slam/bow_matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::AddSharedPoints;
using testing::CameraAt;
using testing::ObserveScene;
using testing::RandomScene;

constexpr int kPoints = 100;
constexpr uint32_t kNodes = 5;

vocab::FeatureVector NodesByModulo(const std::vector<int>& point_of_feature) {
  vocab::FeatureVector fv;
  for (size_t j = 0; j < point_of_feature.size(); ++j) {
    fv[static_cast<uint32_t>(point_of_feature[j]) % kNodes].push_back(static_cast<uint32_t>(j));
  }
  return fv;
}

// A frame that sees the keyframe's features in shuffled order, descriptors with 3 bits flipped,
// keypoints rotated by `angle` degrees.
feature::Frame ShuffledFrame(const map::KeyFrame& kf, const std::vector<int>& perm, float angle) {
  feature::Frame f = kf.frame;
  f.descriptors = cv::Mat(static_cast<int>(perm.size()), 32, CV_8U);
  for (size_t j = 0; j < perm.size(); ++j) {
    kf.frame.descriptors.row(perm[j]).copyTo(f.descriptors.row(static_cast<int>(j)));
    f.descriptors.at<uint8_t>(static_cast<int>(j), j % 32) ^= 0x7;
    f.keypoints[j] = kf.frame.keypoints[perm[j]];
    f.keypoints[j].angle = angle;
  }
  f.keypoints_undistorted = f.keypoints;
  return f;
}

struct Fixture {
  map::Map map;
  testing::Scene scene = RandomScene(kPoints, 5);
  std::shared_ptr<map::KeyFrame> kf;
  std::vector<int> perm;  // frame feature j sees scene point perm[j]
  Fixture() {
    kf = ObserveScene(&map, scene, CameraAt(0.0));
    AddSharedPoints(&map, scene, {kf}, 0, kPoints);
    std::vector<int> identity(kPoints);
    std::iota(identity.begin(), identity.end(), 0);
    kf->bow_features = NodesByModulo(identity);
    perm = identity;
    std::shuffle(perm.begin(), perm.end(), std::mt19937(9));
  }
};

TEST(BowMatcher, KeyFrameToFrameMatchesWithinNodesOnly) {
  Fixture fx;
  const feature::Frame frame = ShuffledFrame(*fx.kf, fx.perm, 30.0f);
  vocab::FeatureVector fv = NodesByModulo(fx.perm);
  // The features of points 0..9 are filed under another node: they cannot be matched.
  vocab::FeatureVector misplaced;
  for (const auto& [node, features] : fv) {
    for (uint32_t j : features) {
      const uint32_t n = fx.perm[j] < 10 ? (node + 1) % kNodes : node;
      misplaced[n].push_back(j);
    }
  }
  for (auto& [node, features] : misplaced) std::sort(features.begin(), features.end());
  const auto matches = SearchByBoW(*fx.kf, frame, misplaced);
  ASSERT_EQ(matches.size(), frame.size());
  EXPECT_EQ(CountMatches(matches), kPoints - 10);
  for (size_t j = 0; j < matches.size(); ++j) {
    if (fx.perm[j] < 10) {
      EXPECT_EQ(matches[j], nullptr) << j;
    } else {
      EXPECT_EQ(matches[j], fx.kf->points[fx.perm[j]]) << j;
    }
  }
}

TEST(BowMatcher, OrientationAndRatioChecksDropInconsistentMatches) {
  Fixture fx;
  feature::Frame frame = ShuffledFrame(*fx.kf, fx.perm, 30.0f);
  // Six features rotated inconsistently, each into its own histogram bin: dropped.
  for (int k = 0; k < 6; ++k) frame.keypoints_undistorted[k].angle = 100.0f + 30.0f * k;
  // Feature 10 gets a twin under the same node (another feature's descriptor made equal to it):
  // ambiguous for the ratio test, so neither is matched.
  int twin = 11;
  while (fx.perm[twin] % kNodes != fx.perm[10] % kNodes) ++twin;
  frame.descriptors.row(10).copyTo(frame.descriptors.row(twin));
  const auto matches = SearchByBoW(*fx.kf, frame, NodesByModulo(fx.perm));
  for (int k = 0; k < 6; ++k) EXPECT_EQ(matches[k], nullptr) << k;
  EXPECT_EQ(matches[10], nullptr);
  EXPECT_EQ(matches[twin], nullptr);
  EXPECT_EQ(CountMatches(matches), kPoints - 6 - 2);
  BowMatchOptions no_orientation;
  no_orientation.check_orientation = false;
  EXPECT_EQ(CountMatches(SearchByBoW(*fx.kf, frame, NodesByModulo(fx.perm), no_orientation)),
            kPoints - 2);
}

TEST(BowMatcher, KeyFrameToKeyFrameReturnsTheOtherKeyFramesPoints) {
  Fixture fx;
  // A second keyframe from 0.3 m to the side with its own map points (as before a loop closes).
  auto kf2 = ObserveScene(&fx.map, fx.scene, CameraAt(0.3));
  AddSharedPoints(&fx.map, fx.scene, {kf2}, 0, kPoints);
  kf2->bow_features = fx.kf->bow_features;
  // Points 90..99 of keyframe 2 are bad: never matched.
  for (int i = 90; i < kPoints; ++i) kf2->points[i]->bad = true;
  const auto matches = SearchByBoW(*fx.kf, *kf2);
  ASSERT_EQ(matches.size(), fx.kf->points.size());
  EXPECT_EQ(CountMatches(matches), 90);
  for (int i = 0; i < 90; ++i) EXPECT_EQ(matches[i], kf2->points[i]) << i;
  // Keypoints without a map point in keyframe 1 do not take part.
  fx.kf->points[3] = nullptr;
  EXPECT_EQ(SearchByBoW(*fx.kf, *kf2)[3], nullptr);
}

TEST(BowMatcher, OptionsCheck) {
  BowMatchOptions o;
  o.ratio = 0.0f;
  EXPECT_THROW(o.Check(), InputError);
  o = {};
  o.max_distance = 300;
  EXPECT_THROW(o.Check(), InputError);
}

}  // namespace
}  // namespace moslam::slam
