#include "moslam/optim/pose_optimizer.h"

#include <random>

#include <gtest/gtest.h>

#include "moslam/optim/test_scene.h"
#include "moslam/testing/error_of.h"

namespace moslam::optim {
namespace {

struct Errors {
  double translation = 0.0;  // metres
  double angle = 0.0;        // radians
};

Errors PoseError(const geometry::SE3& a, const geometry::SE3& b) {
  const geometry::SE3 d = a * b.Inverse();
  return {d.translation().norm(), geometry::RotationAngle(d.rotation())};
}

constexpr double kDegree = M_PI / 180.0;

// Recovers a pose perturbed by 5 cm / 3 deg from noisy observations with 25 % gross outliers,
// and classifies them: every gross outlier is flagged, and at most ~10 % of the true inliers are
// (the 95 % chi-square test rejects about 5 % of Gaussian-noise inliers by design).
void ExpectRecovers(double stereo_fraction, uint32_t seed) {
  std::mt19937 rng(seed);
  const CameraModel camera = test::TestCamera();
  for (int trial = 0; trial < 5; ++trial) {
    const test::PoseScene scene = test::MakePoseScene(rng, camera, 300, stereo_fraction, 0.25);
    const geometry::SE3 init = test::RandomPerturbation(rng, 0.05, 3 * kDegree) * scene.T_cam_world;
    const PoseOptimizerResult result =
        OptimizePose(camera, init, scene.points_world, scene.observations);
    const Errors e = PoseError(result.T_cam_world, scene.T_cam_world);
    EXPECT_LT(e.translation, 0.01) << "trial " << trial;
    EXPECT_LT(e.angle, 0.1 * kDegree) << "trial " << trial;

    int outliers = 0, flagged = 0, flagged_outliers = 0, inliers = 0, kept = 0;
    for (size_t i = 0; i < scene.observations.size(); ++i) {
      outliers += scene.is_outlier[i];
      flagged += !result.inlier[i];
      flagged_outliers += scene.is_outlier[i] && !result.inlier[i];
      kept += result.inlier[i];
      inliers += !scene.is_outlier[i];
    }
    ASSERT_GT(outliers, 40);
    EXPECT_EQ(flagged_outliers, outliers) << "outlier recall, trial " << trial;
    EXPECT_GT(double(flagged_outliers) / flagged, 0.75) << "outlier precision, trial " << trial;
    EXPECT_GT(double(kept) / inliers, 0.88) << "inliers kept, trial " << trial;
    EXPECT_EQ(result.num_inliers, kept);
    EXPECT_GT(result.final_cost, 0.0);
  }
}

TEST(OptimizePose, RecoversPerturbedPoseMonocular) { ExpectRecovers(0.0, 11); }
TEST(OptimizePose, RecoversPerturbedPoseStereo) { ExpectRecovers(1.0, 12); }
TEST(OptimizePose, RecoversPerturbedPoseMixed) { ExpectRecovers(0.5, 13); }

TEST(OptimizePose, FewerThanThreeObservationsReturnUnchanged) {
  std::mt19937 rng(20);
  const CameraModel camera = test::TestCamera();
  const test::PoseScene scene = test::MakePoseScene(rng, camera, 2, 0.5, 0.0);
  const geometry::SE3 init = test::RandomPerturbation(rng, 0.05, 3 * kDegree) * scene.T_cam_world;
  const PoseOptimizerResult result =
      OptimizePose(camera, init, scene.points_world, scene.observations);
  EXPECT_EQ(result.T_cam_world.Matrix(), init.Matrix());
  EXPECT_EQ(result.inlier, std::vector<bool>(2, false));
  EXPECT_EQ(result.num_inliers, 0);
  const PoseOptimizerResult empty = OptimizePose(camera, init, {}, {});
  EXPECT_EQ(empty.T_cam_world.Matrix(), init.Matrix());
  EXPECT_TRUE(empty.inlier.empty());
}

// An observation that starts as an outlier does not pull the pose in the first round. Here half
// the observations are consistent with the true pose and half with a pose 30 cm away; marking the
// second half as initial outliers makes the optimizer converge to the first pose (and flag the
// second half), while without the flags the estimate is pulled away from it.
TEST(OptimizePose, InitialOutlierHonoured) {
  std::mt19937 rng(21);
  const CameraModel camera = test::TestCamera();
  const test::PoseScene scene = test::MakePoseScene(rng, camera, 200, 1.0, 0.0);
  const geometry::SE3 other = test::RandomPerturbation(rng, 0.3, 2 * kDegree) * scene.T_cam_world;
  std::vector<Observation> observations = scene.observations;
  std::vector<bool> initial_outlier(observations.size(), false);
  for (size_t i = 0; i < observations.size(); i += 2) {
    const Eigen::Vector3d ideal = test::Project(camera, other * scene.points_world[i]);
    observations[i].pixel = ideal.head<2>();
    observations[i].u_right = ideal.z();
    initial_outlier[i] = true;
  }
  const PoseOptimizerResult result = OptimizePose(camera, scene.T_cam_world, scene.points_world,
                                                  observations, {}, initial_outlier);
  EXPECT_LT(PoseError(result.T_cam_world, scene.T_cam_world).translation, 0.01);
  int flagged_marked = 0;
  for (size_t i = 0; i < observations.size(); i += 2) flagged_marked += !result.inlier[i];
  EXPECT_GE(flagged_marked, 95);  // 100 marked; a few may fit both poses
  // Without the flags the same data pull the estimate away from the true pose.
  const PoseOptimizerResult unflagged =
      OptimizePose(camera, scene.T_cam_world, scene.points_world, observations);
  EXPECT_GT(PoseError(unflagged.T_cam_world, scene.T_cam_world).translation, 0.05);
}

TEST(OptimizePose, AllInitialOutliersLeavePoseUnchanged) {
  std::mt19937 rng(22);
  const CameraModel camera = test::TestCamera();
  const test::PoseScene scene = test::MakePoseScene(rng, camera, 50, 0.5, 0.0);
  const geometry::SE3 init = test::RandomPerturbation(rng, 0.05, 3 * kDegree) * scene.T_cam_world;
  const PoseOptimizerResult result = OptimizePose(
      camera, init, scene.points_world, scene.observations, {}, std::vector<bool>(50, true));
  EXPECT_EQ(result.T_cam_world.Matrix(), init.Matrix());
}

TEST(OptimizePose, PointBehindCameraIsOutlier) {
  std::mt19937 rng(23);
  const CameraModel camera = test::TestCamera();
  test::PoseScene scene = test::MakePoseScene(rng, camera, 100, 0.5, 0.0);
  // Mirror one point through the camera centre: behind the camera, same ray.
  const geometry::SE3& T = scene.T_cam_world;
  scene.points_world[7] = T.Inverse() * (-(T * scene.points_world[7]));
  const PoseOptimizerResult result =
      OptimizePose(camera, T, scene.points_world, scene.observations);
  EXPECT_FALSE(result.inlier[7]);
  EXPECT_LT(PoseError(result.T_cam_world, T).translation, 0.01);
}

TEST(OptimizePose, DeterministicWithOneThread) {
  std::mt19937 rng(24);
  const CameraModel camera = test::TestCamera();
  const test::PoseScene scene = test::MakePoseScene(rng, camera, 500, 0.5, 0.2);
  const geometry::SE3 init = test::RandomPerturbation(rng, 0.05, 3 * kDegree) * scene.T_cam_world;
  const PoseOptimizerResult a = OptimizePose(camera, init, scene.points_world, scene.observations);
  const PoseOptimizerResult b = OptimizePose(camera, init, scene.points_world, scene.observations);
  // Bitwise: exact equality of every coefficient.
  EXPECT_EQ(a.T_cam_world.rotation().coeffs(), b.T_cam_world.rotation().coeffs());
  EXPECT_EQ(a.T_cam_world.translation(), b.T_cam_world.translation());
  EXPECT_EQ(a.inlier, b.inlier);
  EXPECT_EQ(a.final_cost, b.final_cost);
  // More threads: same answer up to the order of floating-point sums.
  PoseOptimizerOptions threads;
  threads.num_threads = 2;
  const PoseOptimizerResult c =
      OptimizePose(camera, init, scene.points_world, scene.observations, threads);
  EXPECT_LT((c.T_cam_world.translation() - a.T_cam_world.translation()).norm(), 1e-9);
  EXPECT_EQ(c.inlier, a.inlier);
}

TEST(PoseOptimizerOptions, CheckNamesTheField) {
  auto error = [](auto mutate) {
    PoseOptimizerOptions options;
    mutate(options);
    return testing::ErrorOf([&] { options.Check(); });
  };
  EXPECT_NO_THROW(PoseOptimizerOptions().Check());
  EXPECT_NE(error([](auto& o) { o.rounds = 0; }).find("rounds"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.iterations_per_round = 0; }).find("iterations_per_round"),
            std::string::npos);
  EXPECT_NE(error([](auto& o) { o.chi2_mono = 0; }).find("chi2_mono"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.chi2_stereo = -1; }).find("chi2_stereo"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.robust_rounds = 5; }).find("robust_rounds"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.num_threads = 0; }).find("num_threads"), std::string::npos);
  const std::vector<Eigen::Vector3d> points(3, Eigen::Vector3d(0, 0, 1));
  const std::vector<Observation> observations(3);
  PoseOptimizerOptions bad;
  bad.rounds = 0;
  EXPECT_NE(testing::ErrorOf([&] {
              OptimizePose(test::TestCamera(), geometry::SE3(), points, observations, bad);
            }).find("rounds"),
            std::string::npos);
}

}  // namespace
}  // namespace moslam::optim
