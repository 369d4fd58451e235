#include "moslam/slam/static_scores.h"

#include <cmath>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "moslam/optim/pose_optimizer.h"
#include "moslam/slam/test_scene.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

using testing::CameraAt;

std::shared_ptr<map::MapPoint> Point(map::Map* map, const Eigen::Vector3d& x,
                                     const std::shared_ptr<map::KeyFrame>& kf) {
  return map->CreateMapPoint(x, kf);
}

TEST(StaticScores, InliersStayFullWeightAndOutliersFallAndAreCulled) {
  map::Map map;
  const testing::Scene scene = testing::RandomScene(2, 1);
  const auto kf = testing::ObserveScene(&map, scene, CameraAt(0.0));
  const auto still = Point(&map, scene.points[0], kf), moving = Point(&map, scene.points[1], kf);
  StaticScores scores;
  EXPECT_DOUBLE_EQ(scores.Weight(still->id), 1.0);  // never judged: the prior, full weight
  for (int frame = 0; frame < 4; ++frame) {
    scores.Observe(still, 2.0, optim::kChi2Stereo);    // a typical inlier
    scores.Observe(moving, 60.0, optim::kChi2Stereo);  // ~4.5 px off at level 0
    EXPECT_DOUBLE_EQ(scores.Weight(still->id), 1.0) << frame;
    EXPECT_FALSE(scores.ShouldCull(still->id));
  }
  EXPECT_LT(scores.Probability(moving->id), 0.05);
  EXPECT_LE(scores.Weight(moving->id), 0.1);
  EXPECT_TRUE(scores.ShouldCull(moving->id));
  // One frame is never decisive: a single large error leaves a long-static point at full weight.
  scores.Observe(still, 500.0, optim::kChi2Stereo);
  EXPECT_DOUBLE_EQ(scores.Weight(still->id), 1.0);
  EXPECT_FALSE(scores.ShouldCull(still->id));
}

TEST(StaticScores, NoCullBeforeMinJudgedAndNothingWhenDisabled) {
  map::Map map;
  const testing::Scene scene = testing::RandomScene(1, 2);
  const auto kf = testing::ObserveScene(&map, scene, CameraAt(0.0));
  const auto p = Point(&map, scene.points[0], kf);
  StaticScoreOptions options;
  options.min_judged = 5;
  StaticScores scores(options);
  for (int i = 0; i < 4; ++i) scores.Observe(p, 100.0, optim::kChi2Mono);
  EXPECT_FALSE(scores.ShouldCull(p->id));  // 4 of the 5 frames
  scores.Observe(p, 100.0, optim::kChi2Mono);
  EXPECT_TRUE(scores.ShouldCull(p->id));

  options.enabled = false;
  StaticScores off(options);
  for (int i = 0; i < 6; ++i) off.Observe(p, 100.0, optim::kChi2Mono);
  EXPECT_DOUBLE_EQ(off.Weight(p->id), 1.0);
  EXPECT_FALSE(off.ShouldCull(p->id));
}

TEST(StaticScores, PruneForgetsErasedPoints) {
  map::Map map;
  const testing::Scene scene = testing::RandomScene(2, 3);
  const auto kf = testing::ObserveScene(&map, scene, CameraAt(0.0));
  auto a = Point(&map, scene.points[0], kf), b = Point(&map, scene.points[1], kf);
  StaticScores scores;
  scores.Observe(a, 1.0, optim::kChi2Mono);
  scores.Observe(b, 1.0, optim::kChi2Mono);
  map.EraseMapPoint(b);
  EXPECT_EQ(scores.Prune(), 1u);
  EXPECT_EQ(scores.size(), 1u);
}

TEST(StaticScores, OptionsAreChecked) {
  StaticScoreOptions o;
  o.prior = 1.0;
  EXPECT_THROW(o.Check(), InputError);
  o = {};
  o.cull_probability = 0.001;  // below the clamp's floor (max_log_odds 4: 0.018)
  EXPECT_THROW(o.Check(), InputError);
  o = {};
  o.min_weight = 0.0;
  EXPECT_THROW(o.Check(), InputError);
  EXPECT_NO_THROW(StaticScoreOptions{}.Check());
}

// A tracked sequence in miniature: 150 static points 2-5 m away and 40 on a box 2.5 m in front of
// the camera (a fifth of the matches) that starts moving sideways at frame 3, 4 mm in the first
// frame, 4 mm more each frame up to 3 cm (a cart pushed off). Every frame the pose is optimized
// from the last one, matched exactly (stereo observations), with the scores' weights, and the
// residuals update the scores, as the tracker does. The box's points must lose their weight (and be
// culled) while the static points keep theirs, and the weighted poses must stay closer to the truth
// than unweighted ones.
struct MovingBoxRun {
  double max_error_m = 0.0;        // largest camera position error over the frames
  double max_error_late_m = 0.0;   // ... from frame 6 on, after the evidence
  double mean_box_weight = 1.0;    // at the end
  double min_static_weight = 1.0;  // at the end
  int box_culled = 0, static_culled = 0;
};

constexpr int kStatic = 150, kBox = 40;

MovingBoxRun RunMovingBox(bool weighted) {
  map::Map map;
  testing::Scene scene = testing::RandomScene(kStatic + kBox, 7);
  // An office: the static points on walls and furniture 2-5 m away, the box 2.5 m away.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> x(-1.5, 1.5), y(-1.0, 1.0), z(2.0, 5.0);
  for (int k = 0; k < kStatic; ++k) {
    const double depth = z(rng);
    scene.points[k] = Eigen::Vector3d(x(rng) * depth / 2.5, y(rng) * depth / 2.5, depth);
  }
  for (int k = kStatic; k < kStatic + kBox; ++k) {
    const int j = k - kStatic;
    scene.points[k] = Eigen::Vector3d(-0.4 + 0.08 * (j % 10), -0.3 + 0.15 * (j / 10), 2.5);
  }
  const auto kf = testing::ObserveScene(&map, scene, CameraAt(0.0));
  std::vector<std::shared_ptr<map::MapPoint>> points;
  for (const Eigen::Vector3d& x : scene.points) points.push_back(Point(&map, x, kf));
  const optim::CameraModel model{535.0, 535.0, 320.0, 240.0, 40.0};
  StaticScores scores;
  MovingBoxRun run;
  geometry::SE3 T_estimate = CameraAt(0.0), velocity;
  double box_offset = 0.0;
  std::vector<bool> culled(points.size(), false);
  for (int frame = 1; frame <= 12; ++frame) {
    const geometry::SE3 T_true = CameraAt(0.01 * frame);  // the camera moves 1 cm a frame
    // Pushed: it starts slowly (4 mm in its first frame, under 1.5 px) and speeds up.
    if (frame >= 3) box_offset += std::min(0.03, 0.004 * (frame - 2));
    std::vector<Eigen::Vector3d> world;
    std::vector<optim::Observation> observations;
    std::vector<double> weights;
    std::vector<size_t> index;
    for (size_t i = 0; i < points.size(); ++i) {
      if (culled[i]) continue;
      Eigen::Vector3d seen = scene.points[i];
      if (i >= kStatic) seen.x() += box_offset;  // where the box's point really is now
      const Eigen::Vector3d p = T_true * seen;
      optim::Observation o;
      o.pixel =
          Eigen::Vector2d(model.fx * p.x() / p.z() + model.cx, model.fy * p.y() / p.z() + model.cy);
      o.u_right = o.pixel.x() - model.bf / p.z();
      world.push_back(points[i]->position);  // the map still has it where it was mapped
      observations.push_back(o);
      weights.push_back(weighted ? scores.Weight(points[i]->id) : 1.0);
      index.push_back(i);
    }
    // The tracker's constant-velocity prediction is where the optimization starts.
    const optim::PoseOptimizerResult r =
        optim::OptimizePose(model, velocity * T_estimate, world, observations, {}, {}, weights);
    velocity = r.T_cam_world * T_estimate.Inverse();
    T_estimate = r.T_cam_world;
    const double error =
        (T_estimate.Inverse().translation() - T_true.Inverse().translation()).norm();
    run.max_error_m = std::max(run.max_error_m, error);
    if (frame >= 6) run.max_error_late_m = std::max(run.max_error_late_m, error);
    for (size_t k = 0; k < index.size(); ++k) {
      scores.Observe(points[index[k]], r.chi2[k], optim::kChi2Stereo);
      if (weighted && scores.ShouldCull(points[index[k]]->id)) culled[index[k]] = true;
    }
  }
  double box_sum = 0.0;
  for (size_t i = 0; i < points.size(); ++i) {
    const double w = culled[i] ? 0.0 : scores.Weight(points[i]->id);
    if (i >= kStatic) {
      box_sum += w;
      run.box_culled += culled[i];
    } else {
      run.min_static_weight = std::min(run.min_static_weight, w);
      run.static_culled += culled[i];
    }
  }
  run.mean_box_weight = box_sum / kBox;
  return run;
}

TEST(StaticScores, WeightsFallOnThePointsOfAMovingBox) {
  const MovingBoxRun weighted = RunMovingBox(true);
  EXPECT_LT(weighted.mean_box_weight, 0.1);
  EXPECT_GE(weighted.box_culled, 30) << "of the box's 40 points";
  EXPECT_EQ(weighted.static_culled, 0);
  EXPECT_DOUBLE_EQ(weighted.min_static_weight, 1.0);
  // Its first two frames of motion, under and just over the noise, pull the pose by at most a
  // centimetre and a half; from then on the camera is exact.
  EXPECT_LT(weighted.max_error_m, 0.015);
  EXPECT_LT(weighted.max_error_late_m, 1e-4);
  // Without the scores nothing is culled: the box's points stay in the map.
  const MovingBoxRun plain = RunMovingBox(false);
  EXPECT_EQ(plain.box_culled, 0);
}

}  // namespace
}  // namespace moslam::slam
