#include "moslam/optim/schur_lm.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Geometry>

#include "moslam/optim/cost_functions.h"
#include "moslam/util/check.h"

namespace moslam::optim::internal {
namespace {

using Mat66 = Eigen::Matrix<double, 6, 6>;
using Mat63 = Eigen::Matrix<double, 6, 3>;
using Mat36 = Eigen::Matrix<double, 3, 6>;
using Mat33 = Eigen::Matrix3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Vec3 = Eigen::Vector3d;

// Ceres 2.1's defaults (Solver::Options), which the Ceres path of the bundle adjuster runs with.
constexpr double kFunctionTolerance = 1e-6;
constexpr double kGradientTolerance = 1e-10;
constexpr double kParameterTolerance = 1e-8;
constexpr double kInitialRadius = 1e4;
constexpr double kMaxRadius = 1e16;
constexpr double kMinRadius = 1e-32;
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;
constexpr double kMinRelativeDecrease = 1e-3;
constexpr int kMaxConsecutiveInvalidSteps = 5;

// One active edge at the current variables, residual and Jacobians scaled by sqrt(rho'(s)). A
// monocular edge leaves its third row zero, which adds nothing to the normal equations.
struct EdgeTerms {
  Vec3 r = Vec3::Zero();
  Mat36 J_pose = Mat36::Zero();  // d r / d xi, xi the left perturbation of T_cam_world
  Mat33 J_point = Mat33::Zero();
  Mat63 W = Mat63::Zero();  // J_pose^T J_point (pose and point both free)
  Mat63 Y = Mat63::Zero();  // W V^-1 of the step being solved
};

class Solver {
 public:
  Solver(const BundleProblem& problem, const std::vector<bool>& active,
         const SchurLMOptions& options, double* poses, double* points);
  SchurLMSummary Run();

 private:
  // Cost 1/2 sum rho(s) at the given variables; false when an edge's point is not in front of
  // its camera there (the step that led there is rejected, as Ceres does).
  bool Cost(const double* poses, const double* points, double* cost) const;
  // Residual of active edge k (whitened, unscaled) and, when J_p is not null, d r / d p_cam.
  bool Residual(int k, const double* poses, const double* points, Vec3* r, Vec3* p_cam,
                Mat33* J_p) const;
  double Rho(int k, double s, double* rho1) const;
  void Linearize();
  bool SolveStep(double radius);
  double ModelCostChange() const;
  void MakeCandidate();
  double NormSquared() const;  // of the free variables (Ceres's |x| for its parameter tolerance)

  const BundleProblem& problem_;
  const SchurLMOptions& options_;
  double* poses_;
  double* points_;
  std::vector<int> edges_;         // active edge indices
  std::vector<double> sqrt_info_;  // per active edge
  std::vector<int> free_pose_;     // per pose: index among the free poses or -1
  std::vector<int> free_point_;    // per point: index among the free points or -1
  std::vector<int> pose_of_free_, point_of_free_;
  std::vector<int> point_begin_, point_edges_;  // per free point, its active edges (CSR)
  std::vector<EdgeTerms> terms_;
  std::vector<Mat66> U_;
  std::vector<Vec6> b_;
  std::vector<Mat33> V_, V_inv_;
  std::vector<Vec3> c_;
  Eigen::MatrixXd S_;
  Eigen::VectorXd rhs_, step_pose_, step_point_;
  Eigen::LLT<Eigen::MatrixXd, Eigen::Lower> llt_;
  std::vector<double> candidate_poses_, candidate_points_;
  double gradient_max_norm_ = 0.0;
};

Solver::Solver(const BundleProblem& problem, const std::vector<bool>& active,
               const SchurLMOptions& options, double* poses, double* points)
    : problem_(problem), options_(options), poses_(poses), points_(points) {
  const int num_poses = static_cast<int>(problem.T_cam_world.size());
  const int num_points = static_cast<int>(problem.points_world.size());
  free_pose_.assign(num_poses, -1);
  free_point_.assign(num_points, -1);
  std::vector<int> point_count(num_points, 0);
  for (size_t e = 0; e < problem.edges.size(); ++e) {
    if (!active[e]) continue;
    const BundleProblem::Edge& edge = problem.edges[e];
    edges_.push_back(static_cast<int>(e));
    sqrt_info_.push_back(std::sqrt(edge.observation.inv_sigma2));
    if (!problem.pose_fixed[edge.pose] && free_pose_[edge.pose] < 0) {
      free_pose_[edge.pose] = static_cast<int>(pose_of_free_.size());
      pose_of_free_.push_back(edge.pose);
    }
    const bool point_fixed = !problem.point_fixed.empty() && problem.point_fixed[edge.point];
    if (!point_fixed && free_point_[edge.point] < 0) {
      free_point_[edge.point] = static_cast<int>(point_of_free_.size());
      point_of_free_.push_back(edge.point);
    }
    if (!point_fixed) ++point_count[edge.point];
  }
  point_begin_.assign(point_of_free_.size() + 1, 0);
  for (size_t f = 0; f < point_of_free_.size(); ++f) {
    point_begin_[f + 1] = point_begin_[f] + point_count[point_of_free_[f]];
  }
  point_edges_.resize(point_begin_.back());
  std::vector<int> fill(point_begin_.begin(), point_begin_.end() - 1);
  for (size_t k = 0; k < edges_.size(); ++k) {
    const int f = free_point_[problem.edges[edges_[k]].point];
    if (f >= 0) point_edges_[fill[f]++] = static_cast<int>(k);
  }
  terms_.resize(edges_.size());
  U_.resize(pose_of_free_.size());
  b_.resize(pose_of_free_.size());
  V_.resize(point_of_free_.size());
  V_inv_.resize(point_of_free_.size());
  c_.resize(point_of_free_.size());
  candidate_poses_.assign(poses, poses + kPoseSize * num_poses);
  candidate_points_.assign(points, points + 3 * num_points);
}

bool Solver::Residual(int k, const double* poses, const double* points, Vec3* r, Vec3* p_cam,
                      Mat33* J_p) const {
  const BundleProblem::Edge& edge = problem_.edges[edges_[k]];
  const double* pose = poses + kPoseSize * edge.pose;
  const Eigen::Map<const Eigen::Quaterniond> q(pose);
  const Eigen::Map<const Eigen::Vector3d> t(pose + 4);
  *p_cam = q * Eigen::Map<const Vec3>(points + 3 * edge.point) + t;
  r->setZero();
  if (edge.observation.is_stereo()) {
    Eigen::Matrix<double, 3, 3> J;
    if (!ProjectionResidual<3>(problem_.camera, edge.observation, sqrt_info_[k], *p_cam, r->data(),
                               J_p ? &J : nullptr)) {
      return false;
    }
    if (J_p) *J_p = J;
  } else {
    Eigen::Matrix<double, 2, 3> J;
    if (!ProjectionResidual<2>(problem_.camera, edge.observation, sqrt_info_[k], *p_cam, r->data(),
                               J_p ? &J : nullptr)) {
      return false;
    }
    if (J_p) {
      J_p->topRows<2>() = J;
      J_p->row(2).setZero();
    }
  }
  return true;
}

// Huber (Ceres's HuberLoss(a) with a^2 the edge's chi-square threshold): rho(s) = s up to a^2,
// 2 a sqrt(s) - a^2 beyond; rho'(s) into *rho1.
double Solver::Rho(int k, double s, double* rho1) const {
  *rho1 = 1.0;
  if (!options_.robust) return s;
  const double a2 = Chi2Threshold(problem_.edges[edges_[k]].observation, options_.chi2_mono,
                                  options_.chi2_stereo);
  if (s <= a2) return s;
  const double a = std::sqrt(a2);
  const double root = std::sqrt(s);
  *rho1 = a / root;
  return 2.0 * a * root - a2;
}

bool Solver::Cost(const double* poses, const double* points, double* cost) const {
  double sum = 0.0;
  Vec3 r, p_cam;
  for (size_t k = 0; k < edges_.size(); ++k) {
    if (!Residual(static_cast<int>(k), poses, points, &r, &p_cam, nullptr)) return false;
    double rho1;
    sum += Rho(static_cast<int>(k), r.squaredNorm(), &rho1);
  }
  *cost = 0.5 * sum;
  return true;
}

void Solver::Linearize() {
  for (Mat66& U : U_) U.setZero();
  for (Vec6& b : b_) b.setZero();
  for (Mat33& V : V_) V.setZero();
  for (Vec3& c : c_) c.setZero();
  Vec3 p_cam;
  Mat33 J_p;
  for (size_t k = 0; k < edges_.size(); ++k) {
    EdgeTerms& term = terms_[k];
    const BundleProblem::Edge& edge = problem_.edges[edges_[k]];
    // Cost succeeded at these variables, so every edge is in front of its camera.
    MOSLAM_CHECK(Residual(static_cast<int>(k), poses_, points_, &term.r, &p_cam, &J_p));
    double rho1;
    Rho(static_cast<int>(k), term.r.squaredNorm(), &rho1);
    const double scale = std::sqrt(rho1);
    term.r *= scale;
    J_p *= scale;
    const int i = free_pose_[edge.pose];
    const int j = free_point_[edge.point];
    if (i >= 0) {
      term.J_pose = TangentPoseJacobian<3>(J_p, p_cam);
      U_[i].noalias() += term.J_pose.transpose() * term.J_pose;
      b_[i].noalias() += term.J_pose.transpose() * term.r;
    }
    if (j >= 0) {
      const Eigen::Map<const Eigen::Quaterniond> q(poses_ + kPoseSize * edge.pose);
      term.J_point.noalias() = J_p * q.toRotationMatrix();
      V_[j].noalias() += term.J_point.transpose() * term.J_point;
      c_[j].noalias() += term.J_point.transpose() * term.r;
    }
    if (i >= 0 && j >= 0) term.W.noalias() = term.J_pose.transpose() * term.J_point;
  }
  gradient_max_norm_ = 0.0;
  for (const Vec6& b : b_)
    gradient_max_norm_ = std::max(gradient_max_norm_, b.cwiseAbs().maxCoeff());
  for (const Vec3& c : c_)
    gradient_max_norm_ = std::max(gradient_max_norm_, c.cwiseAbs().maxCoeff());
}

// The damped normal equations [U W; W^T V] [dp; dx] = -[b; c], U and V with diag / radius added,
// solved through the reduced camera system (U - W V^-1 W^T) dp = -b + W V^-1 c.
bool Solver::SolveStep(double radius) {
  const int n = static_cast<int>(pose_of_free_.size());
  auto damp = [radius](auto diagonal) {
    return (diagonal.cwiseMax(kMinDiagonal).cwiseMin(kMaxDiagonal) / radius).eval();
  };
  S_.setZero(6 * n, 6 * n);
  rhs_.setZero(6 * n);
  for (int i = 0; i < n; ++i) {
    S_.block<6, 6>(6 * i, 6 * i) = U_[i];
    S_.block<6, 6>(6 * i, 6 * i).diagonal() += damp(U_[i].diagonal());
    rhs_.segment<6>(6 * i) = -b_[i];
  }
  for (size_t f = 0; f < V_.size(); ++f) {
    Mat33 V = V_[f];
    V.diagonal() += damp(V_[f].diagonal());
    const Eigen::LLT<Mat33> llt(V);
    if (llt.info() != Eigen::Success) return false;
    V_inv_[f] = llt.solve(Mat33::Identity());
    const int begin = point_begin_[f], end = point_begin_[f + 1];
    for (int a = begin; a < end; ++a) {
      const int k = point_edges_[a];
      const int i = free_pose_[problem_.edges[edges_[k]].pose];
      if (i < 0) continue;
      EdgeTerms& term = terms_[k];
      term.Y.noalias() = term.W * V_inv_[f];
      rhs_.segment<6>(6 * i).noalias() += term.Y * c_[f];
      for (int a2 = begin; a2 < end; ++a2) {
        const int k2 = point_edges_[a2];
        const int i2 = free_pose_[problem_.edges[edges_[k2]].pose];
        // Lower triangle only: the Cholesky factorization reads nothing else.
        if (i2 < 0 || i2 > i) continue;
        S_.block<6, 6>(6 * i, 6 * i2).noalias() -= term.Y * terms_[k2].W.transpose();
      }
    }
  }
  if (n > 0) {
    llt_.compute(S_);
    if (llt_.info() != Eigen::Success) return false;
    step_pose_ = llt_.solve(rhs_);
    if (!step_pose_.allFinite()) return false;
  } else {
    step_pose_.resize(0);
  }
  step_point_.resize(3 * static_cast<Eigen::Index>(V_.size()));
  for (size_t f = 0; f < V_.size(); ++f) {
    Vec3 rhs = -c_[f];
    for (int a = point_begin_[f]; a < point_begin_[f + 1]; ++a) {
      const int k = point_edges_[a];
      const int i = free_pose_[problem_.edges[edges_[k]].pose];
      if (i >= 0) rhs.noalias() -= terms_[k].W.transpose() * step_pose_.segment<6>(6 * i);
    }
    step_point_.segment<3>(3 * f) = V_inv_[f] * rhs;
  }
  return step_point_.allFinite();
}

// What the linearized model predicts the step saves: 1/2 |r|^2 - 1/2 |r + J d|^2 over the edges.
double Solver::ModelCostChange() const {
  double change = 0.0;
  for (size_t k = 0; k < edges_.size(); ++k) {
    const BundleProblem::Edge& edge = problem_.edges[edges_[k]];
    const EdgeTerms& term = terms_[k];
    Vec3 J_step = Vec3::Zero();
    const int i = free_pose_[edge.pose];
    const int j = free_point_[edge.point];
    if (i >= 0) J_step.noalias() += term.J_pose * step_pose_.segment<6>(6 * i);
    if (j >= 0) J_step.noalias() += term.J_point * step_point_.segment<3>(3 * j);
    change -= term.r.dot(J_step) + 0.5 * J_step.squaredNorm();
  }
  return change;
}

void Solver::MakeCandidate() {
  const SE3LeftManifold manifold;
  for (size_t f = 0; f < pose_of_free_.size(); ++f) {
    const int pose = pose_of_free_[f];
    manifold.Plus(poses_ + kPoseSize * pose, step_pose_.data() + 6 * f,
                  candidate_poses_.data() + kPoseSize * pose);
  }
  for (size_t f = 0; f < point_of_free_.size(); ++f) {
    const int point = point_of_free_[f];
    Eigen::Map<Vec3>(candidate_points_.data() + 3 * point) =
        Eigen::Map<const Vec3>(points_ + 3 * point) + step_point_.segment<3>(3 * f);
  }
}

double Solver::NormSquared() const {
  double norm2 = 0.0;
  for (int pose : pose_of_free_) {
    norm2 += Eigen::Map<const Eigen::Matrix<double, kPoseSize, 1>>(poses_ + kPoseSize * pose)
                 .squaredNorm();
  }
  for (int point : point_of_free_)
    norm2 += Eigen::Map<const Vec3>(points_ + 3 * point).squaredNorm();
  return norm2;
}

SchurLMSummary Solver::Run() {
  SchurLMSummary summary;
  double cost = 0.0;
  if (edges_.empty() || !Cost(poses_, points_, &cost)) return summary;
  summary.iterations = 1;
  Linearize();
  if (gradient_max_norm_ <= kGradientTolerance) return summary;
  double x_norm2 = NormSquared();
  double radius = kInitialRadius;
  double decrease_factor = 2.0;
  int invalid_steps = 0;
  auto reject = [&] {
    radius /= decrease_factor;
    decrease_factor *= 2.0;
    return radius >= kMinRadius;
  };
  while (summary.iterations <= options_.max_iterations) {
    if (options_.stop && options_.stop->load()) break;
    ++summary.iterations;
    double model_change = 0.0;
    if (!SolveStep(radius) || !((model_change = ModelCostChange()) > 0.0)) {
      if (++invalid_steps >= kMaxConsecutiveInvalidSteps || !reject()) break;
      continue;
    }
    invalid_steps = 0;
    const double step_norm = std::sqrt(step_pose_.squaredNorm() + step_point_.squaredNorm());
    if (step_norm <= kParameterTolerance * (std::sqrt(x_norm2) + kParameterTolerance)) break;
    MakeCandidate();
    double candidate_cost = 0.0;
    const bool valid = Cost(candidate_poses_.data(), candidate_points_.data(), &candidate_cost);
    const double cost_change =
        valid ? cost - candidate_cost : -std::numeric_limits<double>::infinity();
    if (std::abs(cost_change) <= kFunctionTolerance * cost) break;
    const double relative_decrease = cost_change / model_change;
    if (!(relative_decrease > kMinRelativeDecrease)) {
      if (!reject()) break;
      continue;
    }
    // Accepted: Nielsen's update of the radius (Ceres's LevenbergMarquardtStrategy::StepAccepted).
    for (int pose : pose_of_free_) {
      std::copy_n(candidate_poses_.data() + kPoseSize * pose, kPoseSize, poses_ + kPoseSize * pose);
    }
    for (int point : point_of_free_) {
      std::copy_n(candidate_points_.data() + 3 * point, 3, points_ + 3 * point);
    }
    cost = candidate_cost;
    x_norm2 = NormSquared();
    const double rho = 2.0 * relative_decrease - 1.0;
    radius = std::min(kMaxRadius, radius / std::max(1.0 / 3.0, 1.0 - rho * rho * rho));
    decrease_factor = 2.0;
    Linearize();
    if (gradient_max_norm_ <= kGradientTolerance) break;
  }
  return summary;
}

}  // namespace

SchurLMSummary SolveSchurLM(const BundleProblem& problem, const std::vector<bool>& active,
                            const SchurLMOptions& options, double* poses, double* points) {
  Solver solver(problem, active, options, poses, points);
  return solver.Run();
}

}  // namespace moslam::optim::internal
