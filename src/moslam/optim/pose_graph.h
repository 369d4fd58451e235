// Pose-graph optimization on Sim(3) (ORB-SLAM2's Optimizer::OptimizeEssentialGraph, Mur-Artal &
// Tardós 2017; Strasdat et al., "Scale drift-aware large scale monocular SLAM", RSS 2010), on
// plain data: vertices are keyframe poses S_cam_world, edges relative similarities measured
// before the loop correction (spanning tree, strong covisibility, old loops) or computed by it
// (the new loop links). The caller (slam/loop_closer) builds the graph from the map.
//
// Residual of an edge (i, j) with measurement S_i_j (maps camera j into camera i):
//   E = S_i_j * S_j_world * S_i_world^-1  (identity when consistent),
//   r = [t(E); 2 vec(q(E)); log s(E)] * sqrt(weight),
// the translation, rotation and log-scale of the error similarity. To first order this is
// Sim(3)'s log (geometry::Sim3::Log) at the identity; ORB-SLAM2 uses the exact log with unit
// information, which agrees at the optimum of a consistent graph and differs only by the
// weighting of large errors. Written as a templated functor for Ceres's automatic
// differentiation, which gives exact derivatives of this residual (no hand-written Jacobian to
// check). Vertex parameters: unit quaternion (Ceres EigenQuaternionManifold), translation and
// log-scale; with fix_scale (stereo/RGB-D, 6 DoF) the log-scale blocks are held constant at 0.
#pragma once

#include <vector>

#include "moslam/geometry/sim3.h"

namespace moslam::optim {

struct PoseGraphProblem {
  std::vector<geometry::Sim3> S_cam_world;  // per vertex, the initial estimate
  std::vector<bool> fixed;                  // per vertex (same size); at least one should be
  struct Edge {
    int i = -1;
    int j = -1;
    geometry::Sim3 S_i_j;  // measured S_i_world * S_j_world^-1
    double weight = 1.0;   // > 0; multiplies the squared residual
  };
  std::vector<Edge> edges;
  // True for stereo/RGB-D (SE(3) poses, scale 1 everywhere): a vertex's scale cannot change.
  bool fix_scale = true;
};

struct PoseGraphOptions {
  int max_iterations = 20;  // Levenberg-Marquardt (ORB-SLAM2: 20)
  int num_threads = 1;
  void Check() const;  // InputError naming the field
};

struct PoseGraphResult {
  std::vector<geometry::Sim3> S_cam_world;  // every vertex (fixed ones unchanged)
  double initial_cost = 0.0;                // 0.5 * sum of squared residuals
  double final_cost = 0.0;
  int iterations = 0;
};

// Residual of one edge at the given vertex estimates (7 values, as above, unweighted).
Eigen::Matrix<double, 7, 1> PoseGraphResidual(const geometry::Sim3& S_i_j,
                                              const geometry::Sim3& S_i_world,
                                              const geometry::Sim3& S_j_world);

// Index out of range, size mismatch or weight <= 0: broken invariant (CHECK). With fix_scale,
// every input vertex must have scale 1 (CHECK): the caller passes SE(3) poses.
PoseGraphResult OptimizePoseGraph(const PoseGraphProblem& problem,
                                  const PoseGraphOptions& options = {});

}  // namespace moslam::optim
