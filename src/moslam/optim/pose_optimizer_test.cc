// Pose-only optimization on synthetic scenes: recovery of a perturbed pose, outlier
// classification, degenerate inputs, options checks and run-to-run determinism.
#include "moslam/optim/pose_optimizer.h"

#include <cstring>
#include <random>

#include <gtest/gtest.h>

#include "moslam/optim/synthetic.h"
#include "moslam/testing/error_of.h"

namespace moslam::optim {
namespace {

struct Errors {
  double translation;  // metres
  double angle;        // radians
};

Errors PoseError(const geometry::SE3& a, const geometry::SE3& b) {
  const geometry::SE3 d = a * b.Inverse();
  return {d.translation().norm(), geometry::RotationAngle(d.rotation())};
}

struct Classification {
  double recall;               // true outliers flagged
  double precision;            // flagged that are true outliers
  double false_positive_rate;  // true inliers flagged
};

Classification Classify(const std::vector<bool>& truth_outlier, const std::vector<bool>& inlier) {
  int tp = 0, flagged = 0, outliers = 0;
  for (size_t i = 0; i < inlier.size(); ++i) {
    outliers += truth_outlier[i];
    flagged += !inlier[i];
    tp += truth_outlier[i] && !inlier[i];
  }
  const int inliers = static_cast<int>(inlier.size()) - outliers;
  return {outliers ? double(tp) / outliers : 1.0, flagged ? double(tp) / flagged : 1.0,
          inliers ? double(flagged - tp) / inliers : 0.0};
}

constexpr double kDeg = M_PI / 180.0;

void ExpectRecovers(int mode, double outlier_fraction, uint32_t seed) {
  std::mt19937 rng(seed);
  for (int trial = 0; trial < 5; ++trial) {
    const synthetic::PoseScene s = synthetic::MakePoseScene(rng, 300, outlier_fraction, mode);
    const geometry::SE3 init = synthetic::Perturb(rng, s.T_true, 0.05, 3.0 * kDeg);
    ASSERT_GT(PoseError(init, s.T_true).translation, 0.04);
    const PoseOptimizerResult r = OptimizePose(s.camera, init, s.points, s.observations);
    const Errors e = PoseError(r.T_cam_world, s.T_true);
    EXPECT_LT(e.translation, 0.01) << "mode " << mode << " trial " << trial;
    EXPECT_LT(e.angle, 0.1 * kDeg) << "mode " << mode << " trial " << trial;
    const Classification c = Classify(s.is_outlier, r.inlier);
    // Gross outliers (>= 20 px) are all caught; the 95 % chi-square test rejects about 5 % of
    // the true inliers by design.
    EXPECT_GE(c.recall, 0.98) << "mode " << mode << " trial " << trial;
    EXPECT_LE(c.false_positive_rate, 0.1) << "mode " << mode << " trial " << trial;
    EXPECT_GE(c.precision, 0.65) << "mode " << mode << " trial " << trial;
    int inliers = 0;
    for (bool b : r.inlier) inliers += b;
    EXPECT_EQ(r.num_inliers, inliers);
    EXPECT_GT(r.final_cost, 0.0);
    // 0.5 chi2 per inlier averages ~ DoF / 2 for correctly whitened noise.
    EXPECT_LT(r.final_cost / r.num_inliers, mode == 1 ? 1.5 * 1.5 : 1.5);
  }
}

TEST(OptimizePose, RecoversMonocular) { ExpectRecovers(0, 0.25, 1); }
TEST(OptimizePose, RecoversStereo) { ExpectRecovers(1, 0.25, 2); }
TEST(OptimizePose, RecoversMixed) { ExpectRecovers(2, 0.2, 3); }
TEST(OptimizePose, RecoversWithThirtyPercentOutliers) { ExpectRecovers(2, 0.3, 4); }

TEST(OptimizePose, FewerThanThreeObservationsIsUnchangedAndAllOutliers) {
  std::mt19937 rng(5);
  const synthetic::PoseScene s = synthetic::MakePoseScene(rng, 2, 0.0, 1);
  const geometry::SE3 init = synthetic::Perturb(rng, s.T_true, 0.05, 3.0 * kDeg);
  const PoseOptimizerResult r = OptimizePose(s.camera, init, s.points, s.observations);
  EXPECT_EQ(r.T_cam_world.Matrix(), init.Matrix());
  EXPECT_EQ(r.inlier, std::vector<bool>(2, false));
  EXPECT_EQ(r.num_inliers, 0);
  const PoseOptimizerResult empty = OptimizePose(s.camera, init, {}, {});
  EXPECT_TRUE(empty.inlier.empty());
  EXPECT_EQ(empty.T_cam_world.Matrix(), init.Matrix());
}

// An observation flagged as an initial outlier does not pull the pose in the first round: a
// scene with 45 % outliers fails without the flags, succeeds with them.
TEST(OptimizePose, InitialOutlierIsHonoured) {
  std::mt19937 rng(6);
  synthetic::PoseScene s = synthetic::MakePoseScene(rng, 200, 0.0, 0);
  // Corrupt a consistent subset: a shifted pose explains them (a coherent wrong hypothesis).
  const geometry::SE3 T_wrong = synthetic::Perturb(rng, s.T_true, 0.5, 10 * kDeg);
  std::vector<bool> truth(s.points.size(), false);
  for (size_t i = 0; i < s.points.size(); i += 2) {
    s.observations[i] = synthetic::Observe(rng, s.camera, T_wrong, s.points[i], false, 1.0, false);
    truth[i] = true;
  }
  PoseOptimizerOptions options;
  options.robust_rounds = 1;
  // All the corrupted ones flagged and also ten correct ones: the correct pose wins and the
  // correct ones come back.
  std::vector<bool> flags = truth;
  for (int i = 1; i < 20; i += 2) flags[i] = true;
  const PoseOptimizerResult r =
      OptimizePose(s.camera, s.T_true, s.points, s.observations, options, flags);
  EXPECT_LT(PoseError(r.T_cam_world, s.T_true).translation, 0.01);
  const Classification c = Classify(truth, r.inlier);
  EXPECT_GE(c.recall, 0.95);
  int back = 0;
  for (int i = 1; i < 20; i += 2) back += r.inlier[i];
  EXPECT_GE(back, 8) << "initial outliers that fit come back";
  // Flagging the correct ones instead pulls the pose to the wrong hypothesis.
  std::vector<bool> wrong_flags(truth.size());
  for (size_t i = 0; i < truth.size(); ++i) wrong_flags[i] = !truth[i];
  const PoseOptimizerResult w =
      OptimizePose(s.camera, s.T_true, s.points, s.observations, options, wrong_flags);
  EXPECT_LT(PoseError(w.T_cam_world, T_wrong).translation, 0.05);
}

TEST(OptimizePose, PointBehindCameraIsOutlier) {
  std::mt19937 rng(7);
  synthetic::PoseScene s = synthetic::MakePoseScene(rng, 50, 0.0, 2);
  const Eigen::Vector3d p_c = s.T_true * s.points[3];
  s.points[3] = s.T_true.Inverse() * Eigen::Vector3d(p_c.x(), p_c.y(), -p_c.z());
  const PoseOptimizerResult r = OptimizePose(s.camera, s.T_true, s.points, s.observations);
  EXPECT_FALSE(r.inlier[3]);
  EXPECT_LT(PoseError(r.T_cam_world, s.T_true).translation, 0.01);
}

TEST(OptimizePose, DeterministicWithOneThread) {
  std::mt19937 rng(8);
  const synthetic::PoseScene s = synthetic::MakePoseScene(rng, 500, 0.2, 2);
  const geometry::SE3 init = synthetic::Perturb(rng, s.T_true, 0.05, 3.0 * kDeg);
  const PoseOptimizerResult a = OptimizePose(s.camera, init, s.points, s.observations);
  const PoseOptimizerResult b = OptimizePose(s.camera, init, s.points, s.observations);
  const Eigen::Matrix4d ma = a.T_cam_world.Matrix(), mb = b.T_cam_world.Matrix();
  EXPECT_EQ(std::memcmp(ma.data(), mb.data(), sizeof(double) * 16), 0);
  EXPECT_EQ(a.inlier, b.inlier);
  EXPECT_EQ(std::memcmp(&a.final_cost, &b.final_cost, sizeof(double)), 0);
}

TEST(PoseOptimizerOptions, CheckNamesTheField) {
  using moslam::testing::ErrorOf;
  const auto error = [](auto mutate) {
    PoseOptimizerOptions o;
    mutate(o);
    return ErrorOf([&] { o.Check(); });
  };
  EXPECT_NO_THROW(PoseOptimizerOptions().Check());
  EXPECT_NE(error([](auto& o) { o.rounds = 0; }).find("rounds"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.iterations_per_round = 0; }).find("iterations_per_round"),
            std::string::npos);
  EXPECT_NE(error([](auto& o) { o.chi2_mono = -1; }).find("chi2_mono"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.chi2_stereo = 0; }).find("chi2_stereo"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.robust_rounds = 5; }).find("robust_rounds"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.num_threads = 0; }).find("num_threads"), std::string::npos);
}

}  // namespace
}  // namespace moslam::optim
