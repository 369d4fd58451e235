#include "moslam/optim/pose_graph.h"

#include <cmath>
#include <memory>

#include <ceres/ceres.h>

#include "moslam/optim/solver_util.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::optim {

void PoseGraphOptions::Check() const {
  if (max_iterations < 1) throw InputError("PoseGraphOptions.max_iterations must be >= 1");
  if (num_threads < 1) throw InputError("PoseGraphOptions.num_threads must be >= 1");
}

namespace {

// A similarity as the functor sees it: quaternion (Eigen order x, y, z, w), translation, scale.
template <typename T>
struct SimT {
  Eigen::Quaternion<T> q;
  Eigen::Matrix<T, 3, 1> t;
  T s;

  SimT operator*(const SimT& o) const { return {q * o.q, s * (q * o.t) + t, s * o.s}; }
  SimT Inverse() const {
    const Eigen::Quaternion<T> qi = q.conjugate();
    return {qi, -(qi * t) / s, T(1) / s};
  }
};

template <typename T>
SimT<T> FromBlocks(const T* q, const T* t, const T* log_s) {
  return {Eigen::Quaternion<T>(q[3], q[0], q[1], q[2]), Eigen::Matrix<T, 3, 1>(t[0], t[1], t[2]),
          exp(log_s[0])};
}

template <typename T>
SimT<T> FromSim3(const geometry::Sim3& S) {
  return {S.rotation().cast<T>(), S.translation().cast<T>(), T(S.scale())};
}

// r = [t(E); 2 vec(q(E)); log s(E)], E = S_i_j * S_j * S_i^-1, q(E) taken with w >= 0.
template <typename T>
void EdgeResidual(const SimT<T>& E, T* r) {
  const T sign = E.q.w() < T(0) ? T(-1) : T(1);
  r[0] = E.t.x();
  r[1] = E.t.y();
  r[2] = E.t.z();
  r[3] = T(2) * sign * E.q.x();
  r[4] = T(2) * sign * E.q.y();
  r[5] = T(2) * sign * E.q.z();
  r[6] = log(E.s);
}

struct EdgeCost {
  EdgeCost(const geometry::Sim3& S_i_j, double weight)
      : S_i_j_(S_i_j), sqrt_weight_(std::sqrt(weight)) {}

  template <typename T>
  bool operator()(const T* qi, const T* ti, const T* si, const T* qj, const T* tj, const T* sj,
                  T* residual) const {
    const SimT<T> S_i = FromBlocks(qi, ti, si);
    const SimT<T> S_j = FromBlocks(qj, tj, sj);
    EdgeResidual(FromSim3<T>(S_i_j_) * S_j * S_i.Inverse(), residual);
    for (int k = 0; k < 7; ++k) residual[k] *= T(sqrt_weight_);
    return true;
  }

  geometry::Sim3 S_i_j_;
  double sqrt_weight_;
};

struct VertexBlocks {
  double q[4];  // x, y, z, w
  double t[3];
  double log_s[1];
};

VertexBlocks Pack(const geometry::Sim3& S) {
  VertexBlocks v;
  const Eigen::Quaterniond& q = S.rotation();
  v.q[0] = q.x(), v.q[1] = q.y(), v.q[2] = q.z(), v.q[3] = q.w();
  for (int k = 0; k < 3; ++k) v.t[k] = S.translation()[k];
  v.log_s[0] = std::log(S.scale());
  return v;
}

geometry::Sim3 Unpack(const VertexBlocks& v) {
  return geometry::Sim3(Eigen::Quaterniond(v.q[3], v.q[0], v.q[1], v.q[2]),
                        Eigen::Vector3d(v.t[0], v.t[1], v.t[2]), std::exp(v.log_s[0]));
}

}  // namespace

Eigen::Matrix<double, 7, 1> PoseGraphResidual(const geometry::Sim3& S_i_j,
                                              const geometry::Sim3& S_i_world,
                                              const geometry::Sim3& S_j_world) {
  Eigen::Matrix<double, 7, 1> r;
  EdgeResidual(
      FromSim3<double>(S_i_j) * FromSim3<double>(S_j_world) * FromSim3<double>(S_i_world).Inverse(),
      r.data());
  return r;
}

PoseGraphResult OptimizePoseGraph(const PoseGraphProblem& problem,
                                  const PoseGraphOptions& options) {
  options.Check();
  const size_t n = problem.S_cam_world.size();
  MOSLAM_CHECK_EQ(problem.fixed.size(), n);
  PoseGraphResult result;
  result.S_cam_world = problem.S_cam_world;
  if (n == 0 || problem.edges.empty()) return result;
  std::vector<VertexBlocks> vertices;
  vertices.reserve(n);
  for (const auto& S : problem.S_cam_world) {
    MOSLAM_CHECK(!problem.fix_scale || std::abs(S.scale() - 1.0) < 1e-9)
        << "fixed-scale pose graph with a vertex of scale " << S.scale();
    vertices.push_back(Pack(S));
  }
  // One manifold for every quaternion block, outliving the problem that borrows it.
  auto quaternion_manifold = std::make_unique<ceres::EigenQuaternionManifold>();
  ceres::Manifold* quaternion = quaternion_manifold.get();
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  for (const auto& e : problem.edges) {
    MOSLAM_CHECK(e.i >= 0 && e.j >= 0 && static_cast<size_t>(e.i) < n &&
                 static_cast<size_t>(e.j) < n && e.i != e.j)
        << "pose graph edge " << e.i << " -> " << e.j << " with " << n << " vertices";
    MOSLAM_CHECK(e.weight > 0.0) << "pose graph edge weight " << e.weight;
    auto* cost = new ceres::AutoDiffCostFunction<EdgeCost, 7, 4, 3, 1, 4, 3, 1>(
        new EdgeCost(e.S_i_j, e.weight));
    VertexBlocks& vi = vertices[static_cast<size_t>(e.i)];
    VertexBlocks& vj = vertices[static_cast<size_t>(e.j)];
    ceres_problem.AddResidualBlock(cost, nullptr, vi.q, vi.t, vi.log_s, vj.q, vj.t, vj.log_s);
  }
  for (size_t k = 0; k < n; ++k) {
    VertexBlocks& v = vertices[k];
    if (!ceres_problem.HasParameterBlock(v.q)) continue;  // isolated vertex
    ceres_problem.SetManifold(v.q, quaternion);
    if (problem.fixed[k]) {
      ceres_problem.SetParameterBlockConstant(v.q);
      ceres_problem.SetParameterBlockConstant(v.t);
    }
    if (problem.fixed[k] || problem.fix_scale) ceres_problem.SetParameterBlockConstant(v.log_s);
  }
  ceres::Solver::Options solver = QuietSolverOptions(options.max_iterations, options.num_threads);
  solver.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  ceres::Solver::Summary summary;
  ceres::Solve(solver, &ceres_problem, &summary);
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = static_cast<int>(summary.iterations.size());
  for (size_t k = 0; k < n; ++k) {
    if (!problem.fixed[k]) result.S_cam_world[k] = Unpack(vertices[k]);
  }
  return result;
}

}  // namespace moslam::optim
