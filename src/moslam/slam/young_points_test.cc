#include "moslam/slam/young_points.h"

#include <random>

#include <gtest/gtest.h>

#include "moslam/slam/frame_pose.h"
#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

// The unknown mover's geometry (young_points.h): a far textured wall known for long, without depth
// beyond 5 m as an RGB-D camera sees it, and a close box with depth whose points were made a
// second ago, at positions it has since left (moved sideways by `box_shift` metres).
struct Scene {
  optim::CameraModel camera{525.0, 525.0, 319.5, 239.5, 40.0};  // TUM RGB-D, bf = 0.08 m x fx
  feature::Frame frame;
  std::vector<size_t> indices;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> ages;
  std::vector<bool> on_box;
};

void AddKeypoint(Scene* s, const Eigen::Vector3d& p_cam, bool with_depth, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 0.5);  // pixels
  const double u = s->camera.fx * p_cam.x() / p_cam.z() + s->camera.cx + noise(*rng);
  const double v = s->camera.fy * p_cam.y() / p_cam.z() + s->camera.cy + noise(*rng);
  const cv::KeyPoint kp(static_cast<float>(u), static_cast<float>(v), 31.0f, 0.0f, 0.0f, 0);
  s->frame.keypoints.push_back(kp);
  s->frame.keypoints_undistorted.push_back(kp);
  s->frame.u_right.push_back(with_depth ? static_cast<float>(u - s->camera.bf / p_cam.z()) : -1.0f);
  s->frame.depth.push_back(with_depth ? static_cast<float>(p_cam.z()) : -1.0f);
  s->indices.push_back(s->indices.size());
}

Scene MakeScene(const geometry::SE3& T_cam_world, double box_shift, int num_wall = 200,
                int num_box = 80) {
  Scene s;
  s.frame.scale_factors = {1.0f};
  s.frame.inv_level_sigma2 = {1.0f};
  s.frame.level_sigma2 = {1.0f};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> wall_x(-2.8, 2.8), wall_y(-2.0, 2.0), wall_z(4.6, 6.0);
  std::uniform_real_distribution<double> box_x(-0.3, 0.3), box_y(-0.3, 0.3), box_z(1.2, 1.4);
  std::uniform_real_distribution<double> old_age(12.0, 20.0), young_age(0.5, 1.5);
  const geometry::SE3 T_world_cam = T_cam_world.Inverse();
  for (int k = 0; k < num_wall; ++k) {
    const Eigen::Vector3d pc(wall_x(rng), wall_y(rng), wall_z(rng));
    AddKeypoint(&s, pc, pc.z() < 5.0, &rng);
    s.points.push_back(T_world_cam * pc);
    s.ages.push_back(old_age(rng));
    s.on_box.push_back(false);
  }
  for (int k = 0; k < num_box; ++k) {
    const Eigen::Vector3d pc(box_x(rng), box_y(rng), box_z(rng));
    AddKeypoint(&s, pc, true, &rng);
    // The map point is where the box was: box_shift metres to the camera's left of where it is.
    s.points.push_back(T_world_cam * (pc - Eigen::Vector3d(box_shift, 0.0, 0.0)));
    s.ages.push_back(young_age(rng));
    s.on_box.push_back(true);
  }
  return s;
}

geometry::SE3 TruePose() {
  geometry::Vector6d xi;
  xi << 0.1, -0.05, 0.3, 0.01, 0.02, -0.01;
  return geometry::SE3::Exp(xi);
}

// The motion model's prediction, `scale` x (1 mm, 0.3 mrad) off.
geometry::SE3 Predicted(const geometry::SE3& truth, double scale = 1.0) {
  geometry::Vector6d d;
  d << 0.0008, -0.0004, 0.0006, 0.0002, -0.0002, 0.0001;
  return geometry::SE3::Exp(scale * d) * truth;
}

YoungPointResult RunCheck(const YoungPointCheck& check, const Scene& s,
                          const geometry::SE3& predicted) {
  const optim::PoseOptimizerResult full =
      OptimizeFramePose(s.camera, s.frame, s.indices, s.points, predicted);
  return check.Check(s.camera, s.frame, s.indices, s.points, s.ages, full, predicted);
}

// The check switched on (it is off by default in the system).
YoungPointOptions On() {
  YoungPointOptions o;
  o.enabled = true;
  return o;
}

double PositionError(const geometry::SE3& a, const geometry::SE3& b) {
  return (a.Inverse().translation() - b.Inverse().translation()).norm();
}

TEST(YoungPoints, BoxMovingBeforeAFarWallIsLeftOut) {
  const geometry::SE3 truth = TruePose();
  const Scene s = MakeScene(truth, 0.03);
  const YoungPointResult r = RunCheck(YoungPointCheck{On()}, s, Predicted(truth));
  ASSERT_TRUE(r.checked);
  EXPECT_EQ(r.num_young, 80);
  ASSERT_TRUE(r.moving) << "excess " << r.excess << " over " << r.young_inliers << " inliers";
  ASSERT_EQ(r.excluded.size(), s.indices.size());
  int box_excluded = 0;
  for (size_t k = 0; k < s.indices.size(); ++k) {
    if (s.on_box[k]) {
      box_excluded += r.excluded[k];
      if (r.excluded[k]) {
        EXPECT_FALSE(r.pose.inlier[k]);
        EXPECT_GE(r.pose.chi2[k], ExcludedChi2(optim::kChi2Stereo));
      }
    } else {
      EXPECT_FALSE(r.excluded[k]) << "wall point " << k;
    }
  }
  EXPECT_GE(box_excluded, 76);  // >= 95 % of the box
  // The pose without the box: closer to the truth than the one all matches gave.
  EXPECT_LT(PositionError(r.pose.T_cam_world, truth), 0.004);
  const optim::PoseOptimizerResult full =
      OptimizeFramePose(s.camera, s.frame, s.indices, s.points, Predicted(truth));
  EXPECT_LT(PositionError(r.pose.T_cam_world, truth), PositionError(full.T_cam_world, truth));
  EXPECT_GE(r.pose.num_inliers, 190);
}

// Static: the young points agree with the established ones and with the prediction.
TEST(YoungPoints, StaticSceneIsNotJudgedMoving) {
  const geometry::SE3 truth = TruePose();
  for (double shift : {0.0, 0.001}) {  // still, and within the noise (1 mm at 1.3 m: 0.4 px)
    const Scene s = MakeScene(truth, shift);
    const YoungPointResult r = RunCheck(YoungPointCheck{On()}, s, Predicted(truth));
    EXPECT_TRUE(r.checked);
    EXPECT_FALSE(r.moving) << "shift " << shift << ": excess " << r.excess;
    EXPECT_TRUE(r.excluded.empty());
    EXPECT_LT(r.excess, 20.0);
  }
}

// The far wall leaves translation and yaw nearly free, so the prediction decides where the
// established pose lies (young_points.h): after the motion model has been off by 6 mm on recent
// frames, its prior is looser and a prediction 6 mm off weighs less against the young points than
// while it was good to a millimetre. (It still fires here: the known limit in young_points.h.)
TEST(YoungPoints, PriorLoosensWithTheMotionModelsRecentErrors) {
  const geometry::SE3 truth = TruePose();
  const Scene s = MakeScene(truth, 0.0);
  const geometry::SE3 off = Predicted(truth, 6.0);
  YoungPointCheck check{On()};
  EXPECT_NEAR(check.PriorSigma()[0], YoungPointOptions{}.prior_translation_floor, 1e-12);
  for (int i = 0; i < 40; ++i) check.RecordPrediction(truth, Predicted(truth, 0.5));
  EXPECT_NEAR(check.PriorSigma()[0], YoungPointOptions{}.prior_translation_floor, 1e-12);
  const YoungPointResult tight = RunCheck(check, s, off);
  ASSERT_TRUE(tight.checked);
  for (int i = 0; i < 40; ++i) check.RecordPrediction(truth, off);
  EXPECT_GT(check.PriorSigma()[0], 0.005);
  const YoungPointResult loose = RunCheck(check, s, off);
  ASSERT_TRUE(loose.checked);
  EXPECT_LT(loose.excess, 0.5 * tight.excess)
      << "loose " << loose.excess << " tight " << tight.excess;
}

TEST(YoungPoints, NotCheckedWithoutEnoughMatchesOfBothAges) {
  const geometry::SE3 truth = TruePose();
  // Too few young matches to tell: nothing is judged, however they move.
  Scene s = MakeScene(truth, 0.03, 200, 10);
  YoungPointResult r = RunCheck(YoungPointCheck{On()}, s, truth);
  EXPECT_FALSE(r.checked);
  EXPECT_FALSE(r.moving);
  // All matches of one age (a map just made): the quantile split leaves no young group.
  s = MakeScene(truth, 0.0);
  std::fill(s.ages.begin(), s.ages.end(), 2.0);
  EXPECT_FALSE(RunCheck(YoungPointCheck{On()}, s, truth).checked);
  // Fewer matches than min_matches, and disabled.
  s = MakeScene(truth, 0.03, 40, 15);
  EXPECT_FALSE(RunCheck(YoungPointCheck{On()}, s, truth).checked);
  s = MakeScene(truth, 0.03);
  YoungPointOptions off;
  off.enabled = false;
  EXPECT_FALSE(RunCheck(YoungPointCheck{off}, s, truth).checked);
}

TEST(YoungPoints, OptionsAreChecked) {
  EXPECT_NO_THROW(YoungPointOptions{}.Check());
  auto throws = [](auto change) {
    YoungPointOptions o;
    change(&o);
    EXPECT_THROW(o.Check(), InputError);
  };
  throws([](YoungPointOptions* o) { o->min_matches = 1; });
  throws([](YoungPointOptions* o) { o->age_quantile = 0.0; });
  throws([](YoungPointOptions* o) { o->age_quantile = 1.5; });
  throws([](YoungPointOptions* o) { o->old_fraction = 0.0; });
  throws([](YoungPointOptions* o) { o->min_established = 5; });
  throws([](YoungPointOptions* o) { o->min_young = 2; });
  throws([](YoungPointOptions* o) { o->min_excess = 0.0; });
  throws([](YoungPointOptions* o) { o->excess_per_point = -1.0; });
  throws([](YoungPointOptions* o) { o->prior_scale = 0.0; });
  throws([](YoungPointOptions* o) { o->prior_translation_floor = 0.0; });
  throws([](YoungPointOptions* o) { o->prior_rotation_floor = -1.0; });
  throws([](YoungPointOptions* o) { o->prior_window = 0; });
  EXPECT_THROW(YoungPointCheck{[] {
                 YoungPointOptions o;
                 o.min_young = 0;
                 return o;
               }()},
               InputError);
}

}  // namespace
}  // namespace moslam::slam
