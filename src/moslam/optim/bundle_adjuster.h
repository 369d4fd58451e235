// Bundle adjustment of keyframe poses and points (ORB-SLAM2's Optimizer::LocalBundleAdjustment and
// GlobalBundleAdjustemnt, Mur-Artal & Tardós 2017): monocular and stereo reprojection residuals
// with a Huber loss; some poses are held fixed (the keyframes that see local points but are not
// local themselves). ORB-SLAM2's schedule: optimize, drop edges above the chi-square threshold or
// behind a camera, optimize again without the robust loss; the caller erases the reported outlier
// observations from the map. Ceres with analytic Jacobians (checked numerically in tests).
#pragma once

#include <atomic>
#include <vector>

#include <Eigen/Core>

#include "moslam/geometry/se3.h"
#include "moslam/optim/observation.h"

namespace moslam::optim {

struct BundleProblem {
  CameraModel camera;                      // one camera for every pose (one sensor per run)
  std::vector<geometry::SE3> T_cam_world;  // per pose
  std::vector<bool> pose_fixed;            // per pose (same size)
  std::vector<Eigen::Vector3d> points_world;
  std::vector<bool> point_fixed;  // per point; empty = none fixed
  struct Edge {
    int pose = -1;   // into T_cam_world
    int point = -1;  // into points_world
    Observation observation;
  };
  std::vector<Edge> edges;
};

struct BundleAdjusterOptions {
  int iterations_first = 5;    // robust stage (ORB-SLAM2: 5)
  int iterations_second = 10;  // after outlier removal, no robust loss (ORB-SLAM2: 10)
  double chi2_mono = kChi2Mono;
  double chi2_stereo = kChi2Stereo;
  bool robust = true;   // Huber with delta sqrt(chi2_*) in the first stage
  int num_threads = 1;  // Ceres only; the Schur solver (below) runs on the calling thread
  // Ceres's linear solver of the reduced camera system after the points are eliminated (Schur
  // complement): DENSE_SCHUR up to this many free poses, SPARSE_SCHUR (SuiteSparse) above. 0:
  // always sparse, which optim_benchmark measured as fast as or slightly faster than dense even
  // for a local BA's 7 free keyframes (94 vs 101 ms CPU, 10k edges).
  int dense_schur_max_poses = 0;
  // Which solver runs the Levenberg-Marquardt stages. kSchurLM (schur_lm.h: fixed-size blocks and
  // a dense reduced camera system, 3-6x faster than Ceres on local BAs of RGB-D and stereo maps,
  // docs/RUNNING.md) for problems of up to schur_lm_max_poses free poses, Ceres beyond (its sparse
  // reduced camera system: a global BA over a long trajectory); kCeres always Ceres. Both follow
  // Ceres's Levenberg-Marquardt and reach the same minimum (tests).
  enum class Solver { kSchurLM, kCeres };
  Solver solver = Solver::kSchurLM;
  int schur_lm_max_poses = 300;
  // ORB-SLAM2's abort flag (mbAbortBA): when another thread sets it, the solver stops after its
  // current iteration, the second stage is skipped, and the result so far is returned (edges are
  // still classified). Monocular tracking sets it to get a keyframe into a busy local mapper.
  // Not owned; may be null.
  const std::atomic<bool>* stop = nullptr;
  void Check() const;  // InputError naming the field
};

struct BundleResult {
  std::vector<geometry::SE3> T_cam_world;  // every pose (fixed ones unchanged)
  std::vector<Eigen::Vector3d> points_world;
  std::vector<bool> edge_inlier;  // per edge after the second stage (chi2 and positive depth)
  // 0.5 * sum of squared whitened residuals over the edges that end as inliers, at the input and
  // at the result (the same edges, so the two are comparable).
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;  // Levenberg-Marquardt iterations of both stages
};

// Index out of range or size mismatch: broken invariant (CHECK). An empty problem returns the
// input unchanged.
BundleResult AdjustBundle(const BundleProblem& problem, const BundleAdjusterOptions& options = {});

// Applies `far` to every edge, kDepthWeighted with the strength of the problem's close stereo
// observations per pose (FarStereoWeighting::Strength).
void WeighFarStereo(const FarStereoWeighting& far, BundleProblem* problem);

}  // namespace moslam::optim
