// Relocalization against a small synthetic map (slam/test_scene.h): keyframes that see random
// points with random descriptors, a tiny vocabulary, and frames seen from poses the map never had.
#include "moslam/slam/relocalizer.h"

#include <gtest/gtest.h>

#include "moslam/slam/camera_model.h"
#include "moslam/slam/test_scene.h"
#include "moslam/vocab/test_descriptors.h"

namespace moslam::slam {
namespace {

using testing::AddSharedPoints;
using testing::CameraAt;
using testing::ObserveScene;
using testing::RandomScene;

optim::CameraModel Model() { return CameraModelFor(testing::TestCamera()); }

struct Fixture {
  map::Map map;
  testing::Scene scene = RandomScene(200, 3);
  std::shared_ptr<KeyFrameDatabase> db;
  Fixture() {
    vocab::VocabularyTrainOptions options;
    options.k = 8;
    options.levels = 3;
    // Words seen in every training image weigh 0 (IDF): train on the scene split in two and on
    // unrelated images.
    cv::RNG rng(4);
    const std::vector<cv::Mat> images = {
        scene.descriptors.rowRange(0, 100), scene.descriptors.rowRange(100, 200),
        vocab::test::RandomDescriptors(200, rng), vocab::test::RandomDescriptors(200, rng)};
    db = std::make_shared<KeyFrameDatabase>(
        std::make_shared<const vocab::Vocabulary>(vocab::Vocabulary::Train(images, options)));
    auto a = ObserveScene(&map, scene, CameraAt(0.0));
    auto b = ObserveScene(&map, scene, CameraAt(0.5));
    AddSharedPoints(&map, scene, {a, b}, 0, 200);
    for (const auto& kf : {a, b}) {
      kf->UpdateConnections();
      db->ComputeBow(kf.get());
      db->Add(kf);
    }
  }
};

TEST(Relocalizer, FindsThePoseOfAFrameBetweenKeyFrames) {
  Fixture fx;
  // The frame: the scene seen from x = 0.25 m (no keyframe there), as a keyframe would record it.
  map::Map scratch;
  const geometry::SE3 truth = CameraAt(0.25);
  const feature::Frame frame = ObserveScene(&scratch, fx.scene, truth)->frame;
  std::lock_guard<std::mutex> lock(fx.map.mutex());
  const RelocalizationResult r =
      Relocalize(*fx.db, frame, fx.db->ComputeBow(frame.descriptors), Model());
  ASSERT_TRUE(r.success);
  EXPECT_GE(r.num_candidates, 1);
  EXPECT_GE(r.num_inliers, 150);
  EXPECT_LT((r.T_cam_world.translation() - truth.translation()).norm(), 1e-3);
  ASSERT_EQ(r.points.size(), frame.size());
  // Keypoint i is scene point i: every match points at that point's map point.
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (r.points[i]) {
      EXPECT_EQ(r.points[i], r.keyframe->points[i]) << i;
    }
  }
}

// A short loss (slam/tracker_recovery.cc): the prior says where the camera can be. The true pose
// (0.25 m along x) is kept when the prediction is 0.3 m off and the radius 0.5 m, and refused
// when the prediction is 5 m away: the one place that matches is then no answer.
TEST(Relocalizer, APriorKeepsANearPoseAndRefusesAFarOne) {
  Fixture fx;
  map::Map scratch;
  const geometry::SE3 truth = CameraAt(0.25);
  const feature::Frame frame = ObserveScene(&scratch, fx.scene, truth)->frame;
  const Eigen::Vector3d center = truth.Inverse().translation();
  std::lock_guard<std::mutex> lock(fx.map.mutex());
  const KeyFrameBow bow = fx.db->ComputeBow(frame.descriptors);

  RelocalizationPrior near;
  near.camera_center = center + Eigen::Vector3d(0.3, 0.0, 0.0);
  near.radius = 0.5;
  const RelocalizationResult kept = Relocalize(*fx.db, frame, bow, Model(), {}, near);
  ASSERT_TRUE(kept.success);
  EXPECT_EQ(kept.refused_by_prior, 0);
  EXPECT_LT((kept.T_cam_world.translation() - truth.translation()).norm(), 1e-3);

  RelocalizationPrior far = near;
  far.camera_center = center + Eigen::Vector3d(0.0, 0.0, 5.0);
  const RelocalizationResult refused = Relocalize(*fx.db, frame, bow, Model(), {}, far);
  EXPECT_FALSE(refused.success);
  EXPECT_EQ(refused.keyframe, nullptr);
  EXPECT_GE(refused.refused_by_prior, 1);
  EXPECT_NEAR(refused.nearest_refused, 5.0, 1e-2);
}

TEST(Relocalizer, AnUnknownPlaceGivesNoPose) {
  Fixture fx;
  map::Map scratch;
  const feature::Frame frame = ObserveScene(&scratch, RandomScene(200, 99), CameraAt(0.2))->frame;
  std::lock_guard<std::mutex> lock(fx.map.mutex());
  const RelocalizationResult r =
      Relocalize(*fx.db, frame, fx.db->ComputeBow(frame.descriptors), Model());
  EXPECT_FALSE(r.success);
  EXPECT_EQ(r.keyframe, nullptr);
}

TEST(Relocalizer, ProjectionSearchAddsTheKeyFramesRemainingPoints) {
  Fixture fx;
  map::Map scratch;
  const geometry::SE3 truth = CameraAt(0.25);
  const feature::Frame frame = ObserveScene(&scratch, fx.scene, truth)->frame;
  std::lock_guard<std::mutex> lock(fx.map.mutex());
  const auto kf = fx.map.keyframe(0);
  std::vector<std::shared_ptr<map::MapPoint>> points(frame.size());
  for (size_t i = 0; i < 50; ++i) points[i] = kf->points[i];  // already found
  // From a pose 2 cm off, radius 10 px at level 0: the other 150 points are found where they are.
  const geometry::SE3 guess = CameraAt(0.27);
  const int added = SearchKeyFrameByProjection(*kf, frame, guess, Model(), 10.0f, 100, &points);
  EXPECT_EQ(added, 150);
  for (size_t i = 0; i < points.size(); ++i) EXPECT_EQ(points[i], kf->points[i]) << i;
}

}  // namespace
}  // namespace moslam::slam
