#include "moslam/geometry/alignment.h"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "moslam/util/check.h"

namespace moslam::geometry {
namespace {

// Cross-covariance of the centred sets, sum_i (source_i - mu_s)(target_i - mu_t)^T / n.
struct Moments {
  Eigen::Vector3d mean_source;
  Eigen::Vector3d mean_target;
  Eigen::Matrix3d covariance;  // source x target
  double source_variance = 0;  // mean squared distance of source points to their centroid
};

Moments ComputeMoments(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target) {
  MOSLAM_CHECK_EQ(source.cols(), target.cols());
  const double n = static_cast<double>(source.cols());
  Moments m;
  m.mean_source = source.rowwise().mean();
  m.mean_target = target.rowwise().mean();
  const Eigen::Matrix3Xd s = source.colwise() - m.mean_source;
  const Eigen::Matrix3Xd t = target.colwise() - m.mean_target;
  m.covariance = s * t.transpose() / n;
  m.source_variance = s.squaredNorm() / n;
  return m;
}

// True when the cross-covariance has rank < 2: the rotation is then not determined.
bool IsDegenerate(const Eigen::Matrix3d& covariance) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance);
  const Eigen::Vector3d sv = svd.singularValues();
  return !(sv(0) > 0) || sv(1) <= 1e-12 * sv(0);
}

}  // namespace

std::optional<SE3> AlignHorn(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target) {
  if (source.cols() < 3) return std::nullopt;
  const Moments m = ComputeMoments(source, target);
  if (IsDegenerate(m.covariance)) return std::nullopt;
  const Eigen::Matrix3d& S = m.covariance;
  // Horn's symmetric 4x4 matrix N; the unit quaternion maximizing q^T N q is its eigenvector of
  // the largest eigenvalue. Ordering (w, x, y, z).
  Eigen::Matrix4d N;
  N << S(0, 0) + S(1, 1) + S(2, 2), S(1, 2) - S(2, 1), S(2, 0) - S(0, 2), S(0, 1) - S(1, 0),  //
      S(1, 2) - S(2, 1), S(0, 0) - S(1, 1) - S(2, 2), S(0, 1) + S(1, 0), S(2, 0) + S(0, 2),   //
      S(2, 0) - S(0, 2), S(0, 1) + S(1, 0), -S(0, 0) + S(1, 1) - S(2, 2), S(1, 2) + S(2, 1),  //
      S(0, 1) - S(1, 0), S(2, 0) + S(0, 2), S(1, 2) + S(2, 1), -S(0, 0) - S(1, 1) + S(2, 2);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(N);
  const Eigen::Vector4d v = eig.eigenvectors().col(3);  // eigenvalues ascend
  const Eigen::Quaterniond q(v(0), v(1), v(2), v(3));
  return SE3(q, m.mean_target - q.normalized() * m.mean_source);
}

std::optional<Sim3> AlignUmeyama(const Eigen::Matrix3Xd& source, const Eigen::Matrix3Xd& target,
                                 bool with_scale) {
  if (source.cols() < 3) return std::nullopt;
  const Moments m = ComputeMoments(source, target);
  if (IsDegenerate(m.covariance)) return std::nullopt;
  // Umeyama's Sigma_xy is target x source.
  const Eigen::Matrix3d sigma = m.covariance.transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) d(2, 2) = -1;  // no mirror
  const Eigen::Matrix3d R = svd.matrixU() * d * svd.matrixV().transpose();
  double scale = 1.0;
  if (with_scale) {
    if (!(m.source_variance > 0)) return std::nullopt;
    scale = (svd.singularValues().asDiagonal() * d).trace() / m.source_variance;
  }
  const Eigen::Vector3d t = m.mean_target - scale * R * m.mean_source;
  return Sim3(Eigen::Quaterniond(R), t, scale);
}

}  // namespace moslam::geometry
