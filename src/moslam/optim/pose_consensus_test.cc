#include "moslam/optim/pose_consensus.h"

#include <random>

#include <gtest/gtest.h>

#include "moslam/optim/pose_optimizer.h"
#include "moslam/util/error.h"

namespace moslam::optim {
namespace {

const CameraModel kCamera{535.4, 539.2, 320.1, 247.6, 40.0};

// 60 static points 3-5 m away and 45 on a box 1.3 m in front of the camera (43 % of the matches,
// but most of the information: 1 / depth^2), observed exactly (stereo) from the true pose after
// the box moved `box_shift` since it was mapped.
struct Scene {
  std::vector<Eigen::Vector3d> world, cam;
  std::vector<Observation> observations;
  geometry::SE3 T_true;
  static constexpr int kStatic = 60;

  Scene(const Eigen::Vector3d& box_shift, const geometry::SE3& T) : T_true(T) {
    std::mt19937 rng(4);
    std::uniform_real_distribution<double> u(-0.5, 0.5), z(3.0, 5.0);
    for (int i = 0; i < kStatic; ++i) {
      const double d = z(rng);
      world.emplace_back(u(rng) * d, 0.7 * u(rng) * d, d);
    }
    for (int i = 0; i < 45; ++i)
      world.emplace_back(-0.3 + 0.06 * (i % 9), -0.2 + 0.1 * (i / 9), 1.3);
    for (size_t i = 0; i < world.size(); ++i) {
      const Eigen::Vector3d seen = i < kStatic ? world[i] : Eigen::Vector3d(world[i] + box_shift);
      const Eigen::Vector3d p = T_true * seen;
      Observation o;
      o.pixel = Eigen::Vector2d(kCamera.fx * p.x() / p.z() + kCamera.cx,
                                kCamera.fy * p.y() / p.z() + kCamera.cy);
      o.u_right = o.pixel.x() - kCamera.bf / p.z();
      observations.push_back(o);
      cam.push_back(p);  // the keypoint's own depth: where the point is now
    }
  }
  double Error(const geometry::SE3& T) const {
    return (T.Inverse().translation() - T_true.Inverse().translation()).norm();
  }
};

geometry::SE3 At(double x) {
  return geometry::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(-x, 0, 0));
}

TEST(PoseConsensus, AMovedCloseBoxCannotTakeTheCameraAlong) {
  // The box moved 6 cm sideways (25 px); the prediction is the true pose 2 mm off.
  const Scene s(Eigen::Vector3d(0.06, 0.0, 0.0), At(0.10));
  const geometry::SE3 predicted = At(0.102);
  // Least squares alone, from the prediction: the box's points outweigh the walls.
  const PoseOptimizerResult plain = OptimizePose(kCamera, predicted, s.world, s.observations);
  EXPECT_GT(s.Error(plain.T_cam_world), 0.01) << "the test no longer shows the failure";
  // Counting first: the prediction's inliers are the static points, the optimizer starts there.
  const PoseConsensus c = FindPoseConsensus(kCamera, predicted, s.world, s.observations, s.cam);
  EXPECT_FALSE(c.replaced);
  for (int i = 0; i < Scene::kStatic; ++i) EXPECT_TRUE(c.inlier[i]) << i;
  for (size_t i = Scene::kStatic; i < s.world.size(); ++i) EXPECT_FALSE(c.inlier[i]) << i;
  std::vector<bool> outlier(c.inlier.size());
  for (size_t i = 0; i < outlier.size(); ++i) outlier[i] = !c.inlier[i];
  const PoseOptimizerResult r =
      OptimizePose(kCamera, c.T_cam_world, s.world, s.observations, {}, outlier);
  EXPECT_LT(s.Error(r.T_cam_world), 1e-4);
}

TEST(PoseConsensus, AWrongPredictionIsReplacedByASample) {
  // Nothing moved, but the camera jerked: the prediction is 15 cm off and fits few matches.
  const Scene s(Eigen::Vector3d::Zero(), At(0.0));
  const PoseConsensus c = FindPoseConsensus(kCamera, At(0.15), s.world, s.observations, s.cam);
  EXPECT_TRUE(c.replaced);
  EXPECT_EQ(c.num_inliers, static_cast<int>(s.world.size()));
  EXPECT_LT(s.Error(c.T_cam_world), 1e-6);
}

TEST(PoseConsensus, WithoutDepthThePredictionStands) {
  Scene s(Eigen::Vector3d::Zero(), At(0.0));
  for (auto& p : s.cam) p = Eigen::Vector3d::Constant(std::nan(""));
  const PoseConsensus c = FindPoseConsensus(kCamera, At(0.15), s.world, s.observations, s.cam);
  EXPECT_FALSE(c.replaced);
  EXPECT_EQ(c.num_inliers, c.prediction_inliers);
}

TEST(PoseConsensus, OptionsAreChecked) {
  PoseConsensusOptions o;
  o.iterations = 0;
  EXPECT_THROW(o.Check(), InputError);
  o = {};
  o.min_gain = 0.5;
  EXPECT_THROW(o.Check(), InputError);
  EXPECT_NO_THROW(PoseConsensusOptions{}.Check());
}

}  // namespace
}  // namespace moslam::optim
