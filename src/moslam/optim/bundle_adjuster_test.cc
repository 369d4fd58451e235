#include "moslam/optim/bundle_adjuster.h"

#include <atomic>
#include <random>
#include <utility>

#include <gtest/gtest.h>

#include "moslam/optim/cost_functions.h"
#include "moslam/optim/test_scene.h"
#include "moslam/testing/error_of.h"

namespace moslam::optim {
namespace {

constexpr double kDegree = M_PI / 180.0;

struct EdgeStats {
  int outliers = 0, outliers_flagged = 0, inliers = 0, inliers_kept = 0;
  double inlier_chi2 = 0.0;  // sum over kept edges at the result
  double dof = 0.0;          // sum of residual dimensions over kept edges
};

EdgeStats Stats(const test::BundleScene& scene, const BundleResult& result) {
  EdgeStats s;
  const BundleProblem& problem = scene.problem;
  for (size_t e = 0; e < problem.edges.size(); ++e) {
    const BundleProblem::Edge& edge = problem.edges[e];
    if (scene.edge_outlier[e]) {
      ++s.outliers;
      s.outliers_flagged += !result.edge_inlier[e];
    } else {
      ++s.inliers;
      s.inliers_kept += result.edge_inlier[e];
    }
    if (result.edge_inlier[e]) {
      s.inlier_chi2 += ChiSquare(problem.camera, edge.observation,
                                 result.T_cam_world[edge.pose] * result.points_world[edge.point]);
      s.dof += edge.observation.is_stereo() ? 3 : 2;
    }
  }
  return s;
}

// Translation (m) and rotation angle (rad) between two poses.
std::pair<double, double> Distance(const geometry::SE3& a, const geometry::SE3& b) {
  const geometry::SE3 d = a * b.Inverse();
  return {d.translation().norm(), geometry::RotationAngle(d.rotation())};
}

// From perturbed poses (2 cm / 0.5 deg) and points (5 cm per axis), with 5 % gross outliers:
//  - ORB-SLAM2's schedule (default options) brings the whitened squared error per residual
//    dimension of the kept edges to the noise level (~1; below 1 because the fit absorbs part of
//    the noise), flags the gross outliers, keeps > 90 % of the good edges (the 95 % chi-square
//    test drops ~5 % by design) and leaves fixed poses bitwise unchanged;
//  - run to convergence, it reaches the same minimum as a run started from the true values, and
//    that minimum is within the estimation error of this geometry (0.1 m stereo baseline, 1-1.7
//    px noise: 1-3 cm over the 1.5 m trajectory) of the truth.
void ExpectConverges(double stereo_fraction, int num_fixed, uint32_t seed) {
  std::mt19937 rng(seed);
  const test::BundleScene scene =
      test::MakeBundleScene(rng, 6, num_fixed, 300, 0.7, stereo_fraction, 0.05);
  const BundleResult result = AdjustBundle(scene.problem);
  ASSERT_EQ(result.T_cam_world.size(), scene.true_poses.size());
  for (int i = 0; i < num_fixed; ++i) {
    EXPECT_EQ(result.T_cam_world[i].rotation().coeffs(),
              scene.problem.T_cam_world[i].rotation().coeffs());
    EXPECT_EQ(result.T_cam_world[i].translation(), scene.problem.T_cam_world[i].translation());
  }
  const EdgeStats s = Stats(scene, result);
  ASSERT_GT(s.outliers, 20);
  // A gross error along the epipolar line of a point seen by only two monocular cameras is
  // absorbed by moving the point, so monocular recall can miss a few.
  EXPECT_GE(s.outliers_flagged, stereo_fraction > 0.0 ? s.outliers : 0.9 * s.outliers);
  EXPECT_GT(double(s.inliers_kept) / s.inliers, 0.9);
  EXPECT_LT(s.inlier_chi2 / s.dof, 1.0);
  EXPECT_GT(s.inlier_chi2 / s.dof, 0.5);
  EXPECT_NEAR(result.final_cost, 0.5 * s.inlier_chi2, 1e-9 * s.inlier_chi2);
  EXPECT_GT(result.initial_cost, 10 * result.final_cost);
  EXPECT_GT(result.iterations, 0);

  BundleAdjusterOptions to_convergence;
  to_convergence.iterations_first = 30;
  to_convergence.iterations_second = 30;
  const BundleResult converged = AdjustBundle(scene.problem, to_convergence);
  BundleProblem from_truth = scene.problem;
  from_truth.T_cam_world = scene.true_poses;
  from_truth.points_world = scene.true_points;
  const BundleResult reference = AdjustBundle(from_truth, to_convergence);
  for (size_t i = num_fixed; i < scene.true_poses.size(); ++i) {
    const auto [t_ref, r_ref] = Distance(converged.T_cam_world[i], reference.T_cam_world[i]);
    // Ceres stops when the cost changes by < 1e-6 relative: ~0.1 mm here.
    EXPECT_LT(t_ref, 1e-3) << "pose " << i;
    EXPECT_LT(r_ref, 0.01 * kDegree) << "pose " << i;
    const auto [t_true, r_true] = Distance(converged.T_cam_world[i], scene.true_poses[i]);
    EXPECT_LT(t_true, 0.05) << "pose " << i;
    EXPECT_LT(r_true, 0.5 * kDegree) << "pose " << i;
  }
}

TEST(AdjustBundle, ConvergesStereo) { ExpectConverges(1.0, 1, 31); }
TEST(AdjustBundle, ConvergesMixedMonoStereo) { ExpectConverges(0.5, 1, 32); }
// Monocular: two fixed poses fix the scale as well as the frame.
TEST(AdjustBundle, ConvergesMonocular) { ExpectConverges(0.0, 2, 33); }

TEST(AdjustBundle, PointBehindCameraEdgeIsOutlier) {
  std::mt19937 rng(34);
  test::BundleScene scene = test::MakeBundleScene(rng, 4, 1, 100, 0.8, 0.5, 0.0);
  // A fixed camera at pose 0's place looking the other way: point 0 is behind it.
  const Eigen::Quaterniond turn(Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitY()));
  scene.problem.T_cam_world.push_back(geometry::SE3(turn, Eigen::Vector3d::Zero()) *
                                      scene.true_poses[0]);
  scene.problem.pose_fixed.push_back(true);
  BundleProblem::Edge edge;
  edge.pose = 4;
  edge.point = scene.problem.edges.front().point;
  edge.observation.pixel = {320.0, 240.0};
  scene.problem.edges.push_back(edge);
  ASSERT_GT((scene.problem.T_cam_world[4] * scene.problem.points_world[edge.point]).z(), -100.0);
  ASSERT_LT((scene.problem.T_cam_world[4] * scene.problem.points_world[edge.point]).z(), 0.0);
  const BundleResult result = AdjustBundle(scene.problem);
  EXPECT_FALSE(result.edge_inlier.back());
  int kept = 0;
  for (size_t e = 0; e + 1 < result.edge_inlier.size(); ++e) kept += result.edge_inlier[e];
  EXPECT_GT(kept, 0.9 * (result.edge_inlier.size() - 1));
}

TEST(AdjustBundle, FixedPointsAndUnobservedPosesUnchanged) {
  std::mt19937 rng(35);
  test::BundleScene scene = test::MakeBundleScene(rng, 4, 1, 100, 0.8, 1.0, 0.0);
  scene.problem.point_fixed.assign(100, false);
  for (int j = 0; j < 100; j += 3) scene.problem.point_fixed[j] = true;
  scene.problem.T_cam_world.push_back(test::RandomPose(rng));  // no edges
  scene.problem.pose_fixed.push_back(false);
  scene.problem.points_world.emplace_back(1.0, 2.0, 3.0);  // no edges
  scene.problem.point_fixed.push_back(false);
  const BundleResult result = AdjustBundle(scene.problem);
  for (int j = 0; j < 100; j += 3) EXPECT_EQ(result.points_world[j], scene.problem.points_world[j]);
  EXPECT_EQ(result.points_world.back(), scene.problem.points_world.back());
  EXPECT_EQ(result.T_cam_world.back().translation(),
            scene.problem.T_cam_world.back().translation());
  EXPECT_NE(result.points_world[1], scene.problem.points_world[1]);
}

// Nothing to eliminate: all points fixed (motion-only) or all poses fixed (structure-only).
TEST(AdjustBundle, MotionOnlyAndStructureOnly) {
  std::mt19937 rng(38);
  test::BundleScene scene = test::MakeBundleScene(rng, 4, 1, 150, 0.8, 0.5, 0.0);
  BundleProblem motion = scene.problem;
  motion.points_world = scene.true_points;
  motion.point_fixed.assign(motion.points_world.size(), true);
  const BundleResult m = AdjustBundle(motion);
  for (size_t i = 1; i < scene.true_poses.size(); ++i) {
    EXPECT_LT(Distance(m.T_cam_world[i], scene.true_poses[i]).first, 0.01) << "pose " << i;
  }
  EXPECT_EQ(m.points_world, motion.points_world);

  BundleProblem structure = scene.problem;
  structure.T_cam_world = scene.true_poses;
  structure.pose_fixed.assign(structure.T_cam_world.size(), true);
  const BundleResult s = AdjustBundle(structure);
  // Triangulating over 0.3-0.9 m baselines at 3-8 m leaves points uncertain by more than the
  // 5 cm perturbation, so the check is the fit, not the distance to the true points.
  EXPECT_LT(s.final_cost, 0.1 * s.initial_cost);
  const EdgeStats stats = Stats(scene, s);
  EXPECT_LT(stats.inlier_chi2 / stats.dof, 1.0);
  for (size_t i = 0; i < structure.T_cam_world.size(); ++i) {
    EXPECT_EQ(s.T_cam_world[i].translation(), structure.T_cam_world[i].translation());
  }
}

TEST(AdjustBundle, EmptyProblemReturnsInput) {
  BundleProblem problem;
  problem.camera = test::TestCamera();
  problem.T_cam_world = {geometry::SE3()};
  problem.pose_fixed = {false};
  problem.points_world = {Eigen::Vector3d(1, 2, 3)};
  const BundleResult result = AdjustBundle(problem);
  EXPECT_EQ(result.points_world, problem.points_world);
  EXPECT_EQ(result.T_cam_world[0].translation(), Eigen::Vector3d::Zero());
  EXPECT_TRUE(result.edge_inlier.empty());
  EXPECT_EQ(result.iterations, 0);
}

TEST(AdjustBundle, DeterministicWithOneThread) {
  std::mt19937 rng(36);
  const test::BundleScene scene = test::MakeBundleScene(rng, 5, 1, 200, 0.7, 0.5, 0.05);
  const BundleResult a = AdjustBundle(scene.problem);
  const BundleResult b = AdjustBundle(scene.problem);
  for (size_t i = 0; i < a.T_cam_world.size(); ++i) {
    EXPECT_EQ(a.T_cam_world[i].rotation().coeffs(), b.T_cam_world[i].rotation().coeffs());
    EXPECT_EQ(a.T_cam_world[i].translation(), b.T_cam_world[i].translation());
  }
  EXPECT_EQ(a.points_world, b.points_world);
  EXPECT_EQ(a.edge_inlier, b.edge_inlier);
  EXPECT_EQ(a.final_cost, b.final_cost);
  // More threads: the same minimum up to the order of floating-point sums.
  BundleAdjusterOptions threads;
  threads.num_threads = 2;
  const BundleResult c = AdjustBundle(scene.problem, threads);
  EXPECT_EQ(c.edge_inlier, a.edge_inlier);
  EXPECT_NEAR(c.final_cost, a.final_cost, 1e-6 * a.final_cost);
}

// A stop flag that is already set ends both stages before any step: the input comes back, and
// the edges are still classified (ORB-SLAM2's aborted local BA).
TEST(AdjustBundle, StopFlagEndsTheSolve) {
  std::mt19937 rng(37);
  const test::BundleScene scene = test::MakeBundleScene(rng, 5, 1, 200, 0.7, 0.0, 0.05);
  std::atomic<bool> stop{true};
  BundleAdjusterOptions options;
  options.stop = &stop;
  const BundleResult stopped = AdjustBundle(scene.problem, options);
  EXPECT_LE(stopped.iterations, 1);  // Ceres counts its initial evaluation (iteration 0)
  for (size_t i = 0; i < scene.problem.T_cam_world.size(); ++i) {
    EXPECT_EQ(stopped.T_cam_world[i].translation(), scene.problem.T_cam_world[i].translation());
  }
  EXPECT_EQ(stopped.points_world, scene.problem.points_world);
  EXPECT_EQ(stopped.edge_inlier.size(), scene.problem.edges.size());
  // Not set: the flag changes nothing.
  stop = false;
  const BundleResult a = AdjustBundle(scene.problem, options);
  const BundleResult b = AdjustBundle(scene.problem);
  EXPECT_GT(a.iterations, 0);
  EXPECT_EQ(a.points_world, b.points_world);
  EXPECT_EQ(a.final_cost, b.final_cost);
}

// The sparse reduced-camera solver finds the same optimum as the dense one.
TEST(AdjustBundle, SparseSchurMatchesDense) {
  std::mt19937 rng(37);
  const test::BundleScene scene = test::MakeBundleScene(rng, 6, 1, 300, 0.7, 0.5, 0.05);
  BundleAdjusterOptions dense, sparse;
  dense.solver = sparse.solver = BundleAdjusterOptions::Solver::kCeres;
  dense.dense_schur_max_poses = 40;
  sparse.dense_schur_max_poses = 0;
  const BundleResult a = AdjustBundle(scene.problem, dense);
  const BundleResult b = AdjustBundle(scene.problem, sparse);
  EXPECT_EQ(a.edge_inlier, b.edge_inlier);
  EXPECT_NEAR(a.final_cost, b.final_cost, 1e-6 * a.final_cost);
  for (size_t i = 0; i < a.T_cam_world.size(); ++i) {
    EXPECT_LT((a.T_cam_world[i].translation() - b.T_cam_world[i].translation()).norm(), 1e-6);
  }
}

// The fixed-size Schur solver (schur_lm.h) and Ceres follow the same Levenberg-Marquardt and reach
// the same minimum: the same edges kept, the same cost and poses up to the solvers' tolerances,
// on stereo, mixed and monocular problems, with fixed points, in both stages of the schedule and
// run to convergence.
void ExpectSchurLMMatchesCeres(double stereo_fraction, int num_fixed, bool fix_points,
                               uint32_t seed) {
  std::mt19937 rng(seed);
  test::BundleScene scene =
      test::MakeBundleScene(rng, 8, num_fixed, 400, 0.7, stereo_fraction, 0.05);
  if (fix_points) {
    scene.problem.point_fixed.assign(scene.problem.points_world.size(), false);
    for (size_t j = 0; j < scene.problem.point_fixed.size(); j += 5) {
      scene.problem.point_fixed[j] = true;
    }
  }
  for (const int iterations : {5, 50}) {
    BundleAdjusterOptions lm, ceres;
    lm.iterations_first = ceres.iterations_first = iterations;
    lm.iterations_second = ceres.iterations_second = 2 * iterations;
    ceres.solver = BundleAdjusterOptions::Solver::kCeres;
    const BundleResult a = AdjustBundle(scene.problem, lm);
    const BundleResult b = AdjustBundle(scene.problem, ceres);
    SCOPED_TRACE(::testing::Message()
                 << "stereo " << stereo_fraction << " iterations " << iterations);
    EXPECT_EQ(a.edge_inlier, b.edge_inlier);
    EXPECT_NEAR(a.final_cost, b.final_cost, 1e-5 * b.final_cost);
    EXPECT_EQ(a.initial_cost, b.initial_cost);
    for (size_t i = 0; i < a.T_cam_world.size(); ++i) {
      const auto [dt, dr] = Distance(a.T_cam_world[i], b.T_cam_world[i]);
      EXPECT_LT(dt, 1e-4) << "pose " << i;
      EXPECT_LT(dr, 1e-3 * kDegree) << "pose " << i;
    }
    for (size_t i = 0; i < static_cast<size_t>(num_fixed); ++i) {
      EXPECT_EQ(a.T_cam_world[i].translation(), scene.problem.T_cam_world[i].translation());
    }
    size_t compared = 0;
    for (size_t j = 0; j < a.points_world.size(); ++j) {
      if (fix_points && j % 5 == 0) {
        EXPECT_EQ(a.points_world[j], scene.problem.points_world[j]);
      } else {
        int inliers = 0;
        for (size_t e = 0; e < a.edge_inlier.size(); ++e) {
          inliers += a.edge_inlier[e] && scene.problem.edges[e].point == static_cast<int>(j);
        }
        // A point whose every edge ends as an outlier is held by nothing in the second stage
        // (a monocular one drifts along its ray in the first): the callers drop its edges.
        if (inliers == 0) continue;
        ++compared;
        EXPECT_LT((a.points_world[j] - b.points_world[j]).norm(), 1e-3) << "point " << j;
      }
    }
    EXPECT_GT(compared, a.points_world.size() / 2);
  }
}

TEST(AdjustBundle, SchurLMMatchesCeresStereo) { ExpectSchurLMMatchesCeres(1.0, 1, false, 41); }
TEST(AdjustBundle, SchurLMMatchesCeresMixed) { ExpectSchurLMMatchesCeres(0.5, 2, true, 42); }
TEST(AdjustBundle, SchurLMMatchesCeresMonocular) { ExpectSchurLMMatchesCeres(0.0, 2, false, 43); }

// Above schur_lm_max_poses free poses the Ceres path runs: the same result, bit for bit.
TEST(AdjustBundle, LargeProblemsFallBackToCeres) {
  std::mt19937 rng(44);
  const test::BundleScene scene = test::MakeBundleScene(rng, 6, 1, 300, 0.7, 0.5, 0.05);
  BundleAdjusterOptions small, ceres;
  small.schur_lm_max_poses = 4;  // 5 free poses
  ceres.solver = BundleAdjusterOptions::Solver::kCeres;
  const BundleResult a = AdjustBundle(scene.problem, small);
  const BundleResult b = AdjustBundle(scene.problem, ceres);
  EXPECT_EQ(a.points_world, b.points_world);
  EXPECT_EQ(a.final_cost, b.final_cost);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST(BundleAdjusterOptions, CheckNamesTheField) {
  auto error = [](auto mutate) {
    BundleAdjusterOptions options;
    mutate(options);
    return testing::ErrorOf([&] { options.Check(); });
  };
  EXPECT_NO_THROW(BundleAdjusterOptions().Check());
  EXPECT_NE(error([](auto& o) { o.iterations_first = -1; }).find("iterations_first"),
            std::string::npos);
  EXPECT_NE(error([](auto& o) { o.iterations_second = -1; }).find("iterations_second"),
            std::string::npos);
  EXPECT_NE(error([](auto& o) { o.chi2_mono = 0; }).find("chi2_mono"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.chi2_stereo = 0; }).find("chi2_stereo"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.num_threads = 0; }).find("num_threads"), std::string::npos);
  EXPECT_NE(error([](auto& o) { o.schur_lm_max_poses = -1; }).find("schur_lm_max_poses"),
            std::string::npos);
  EXPECT_NE(error([](auto& o) { o.dense_schur_max_poses = -1; }).find("dense_schur_max_poses"),
            std::string::npos);
}

}  // namespace
}  // namespace moslam::optim
