#include "moslam/slam/mono_initializer.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <future>
#include <numeric>
#include <random>

#include <Eigen/Dense>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/feature/matcher.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::slam {

namespace {

using Points = std::vector<Eigen::Vector2d>;
using Set8 = std::array<size_t, 8>;

// Chi-square thresholds at 95 % (ORB-SLAM2's Initializer): 2 DoF for the homography's point
// transfer, 1 DoF for the distance to an epipolar line; the F score uses the 2-DoF constant so
// that both models are scored on the same scale.
constexpr double kChi2TwoDof = 5.991;
constexpr double kChi2OneDof = 3.841;
// Rays closer than this cosine (about 0.36 degrees) count as parallel (ORB-SLAM2's CheckRT).
constexpr double kParallelCos = 0.99998;

// Hartley normalization: zero mean, unit mean absolute deviation per axis (ORB-SLAM2's
// Normalize). Returns T with normalized = T * pixel.
Eigen::Matrix3d Normalize(const Points& in, Points* out) {
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& p : in) mean += p;
  mean /= static_cast<double>(in.size());
  Eigen::Vector2d dev = Eigen::Vector2d::Zero();
  for (const auto& p : in) dev += (p - mean).cwiseAbs();
  dev /= static_cast<double>(in.size());
  const Eigen::Vector2d s(dev.x() > 0 ? 1.0 / dev.x() : 1.0, dev.y() > 0 ? 1.0 / dev.y() : 1.0);
  out->resize(in.size());
  for (size_t i = 0; i < in.size(); ++i) (*out)[i] = (in[i] - mean).cwiseProduct(s);
  Eigen::Matrix3d T = Eigen::Matrix3d::Identity();
  T(0, 0) = s.x();
  T(1, 1) = s.y();
  T(0, 2) = -mean.x() * s.x();
  T(1, 2) = -mean.y() * s.y();
  return T;
}

Eigen::Matrix3d NullVector(const Eigen::Matrix<double, Eigen::Dynamic, 9>& A) {
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::Matrix<double, 9, 1> h = svd.matrixV().col(8);
  Eigen::Matrix3d M;
  M << h(0), h(1), h(2), h(3), h(4), h(5), h(6), h(7), h(8);
  return M;
}

// Normalized DLT homography x2 = H21 x1 from the points of a set (8 in RANSAC, all inliers in
// the refinement).
template <typename Set>
Eigen::Matrix3d ComputeH21(const Points& p1, const Points& p2, const Set& set) {
  Eigen::Matrix<double, Eigen::Dynamic, 9> A(2 * set.size(), 9);
  for (size_t k = 0; k < set.size(); ++k) {
    const double u1 = p1[set[k]].x(), v1 = p1[set[k]].y();
    const double u2 = p2[set[k]].x(), v2 = p2[set[k]].y();
    A.row(2 * k) << 0, 0, 0, -u1, -v1, -1, v2 * u1, v2 * v1, v2;
    A.row(2 * k + 1) << u1, v1, 1, 0, 0, 0, -u2 * u1, -u2 * v1, -u2;
  }
  return NullVector(A);
}

// Normalized 8-point fundamental matrix x2^T F21 x1 = 0, rank 2 enforced.
template <typename Set>
Eigen::Matrix3d ComputeF21(const Points& p1, const Points& p2, const Set& set) {
  Eigen::Matrix<double, Eigen::Dynamic, 9> A(set.size(), 9);
  for (size_t k = 0; k < set.size(); ++k) {
    const double u1 = p1[set[k]].x(), v1 = p1[set[k]].y();
    const double u2 = p2[set[k]].x(), v2 = p2[set[k]].y();
    A.row(k) << u2 * u1, u2 * v1, u2, v2 * u1, v2 * v1, v2, u1, v1, 1;
  }
  const Eigen::Matrix3d F = NullVector(A);
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(F, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d w = svd.singularValues();
  w(2) = 0.0;
  return svd.matrixU() * w.asDiagonal() * svd.matrixV().transpose();
}

struct Scored {
  double score = 0.0;
  std::vector<bool> inlier;
};

// Symmetric transfer error of a homography, ORB-SLAM2's CheckHomography: each direction adds
// (th - chi2) when under th, and a match is an inlier when under th both ways.
Scored ScoreHomography(const Eigen::Matrix3d& H21, const Eigen::Matrix3d& H12, const Points& p1,
                       const Points& p2, double inv_sigma2) {
  Scored s;
  s.inlier.assign(p1.size(), false);
  for (size_t i = 0; i < p1.size(); ++i) {
    bool in = true;
    const Eigen::Vector3d x2in1 = H12 * p2[i].homogeneous();
    const double chi1 = (p1[i] - x2in1.hnormalized()).squaredNorm() * inv_sigma2;
    if (chi1 > kChi2TwoDof) {
      in = false;
    } else {
      s.score += kChi2TwoDof - chi1;
    }
    const Eigen::Vector3d x1in2 = H21 * p1[i].homogeneous();
    const double chi2 = (p2[i] - x1in2.hnormalized()).squaredNorm() * inv_sigma2;
    if (chi2 > kChi2TwoDof) {
      in = false;
    } else {
      s.score += kChi2TwoDof - chi2;
    }
    s.inlier[i] = in;
  }
  return s;
}

// Distances to the epipolar lines in both images, ORB-SLAM2's CheckFundamental (1-DoF test, score
// with the 2-DoF constant).
Scored ScoreFundamental(const Eigen::Matrix3d& F21, const Points& p1, const Points& p2,
                        double inv_sigma2) {
  Scored s;
  s.inlier.assign(p1.size(), false);
  for (size_t i = 0; i < p1.size(); ++i) {
    bool in = true;
    const Eigen::Vector3d l2 = F21 * p1[i].homogeneous();
    const double n2 = l2.dot(p2[i].homogeneous());
    const double chi1 = n2 * n2 / (l2.x() * l2.x() + l2.y() * l2.y()) * inv_sigma2;
    if (!(chi1 <= kChi2OneDof)) {
      in = false;
    } else {
      s.score += kChi2TwoDof - chi1;
    }
    const Eigen::Vector3d l1 = F21.transpose() * p2[i].homogeneous();
    const double n1 = l1.dot(p1[i].homogeneous());
    const double chi2 = n1 * n1 / (l1.x() * l1.x() + l1.y() * l1.y()) * inv_sigma2;
    if (!(chi2 <= kChi2OneDof)) {
      in = false;
    } else {
      s.score += kChi2TwoDof - chi2;
    }
    s.inlier[i] = in;
  }
  return s;
}

struct Model {
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  Scored scored;
};

Model FindHomography(const Points& p1, const Points& p2, const std::vector<Set8>& sets,
                     double inv_sigma2) {
  Points n1, n2;
  const Eigen::Matrix3d T1 = Normalize(p1, &n1);
  const Eigen::Matrix3d T2 = Normalize(p2, &n2);
  const Eigen::Matrix3d T2_inv = T2.inverse();
  Model best;
  for (const Set8& set : sets) {
    const Eigen::Matrix3d H21 = T2_inv * ComputeH21(n1, n2, set) * T1;
    const Eigen::Matrix3d H12 = H21.inverse();
    if (!H12.allFinite()) continue;
    Scored s = ScoreHomography(H21, H12, p1, p2, inv_sigma2);
    if (s.score > best.scored.score) best = {H21, std::move(s)};
  }
  return best;
}

Model FindFundamental(const Points& p1, const Points& p2, const std::vector<Set8>& sets,
                      double inv_sigma2) {
  Points n1, n2;
  const Eigen::Matrix3d T1 = Normalize(p1, &n1);
  const Eigen::Matrix3d T2 = Normalize(p2, &n2);
  Model best;
  for (const Set8& set : sets) {
    const Eigen::Matrix3d F21 = T2.transpose() * ComputeF21(n1, n2, set) * T1;
    Scored s = ScoreFundamental(F21, p1, p2, inv_sigma2);
    if (s.score > best.scored.score) best = {F21, std::move(s)};
  }
  return best;
}

std::vector<size_t> Inliers(const Scored& s) {
  std::vector<size_t> idx;
  for (size_t i = 0; i < s.inlier.size(); ++i) {
    if (s.inlier[i]) idx.push_back(i);
  }
  return idx;
}

// Departure from ORB-SLAM2, which decomposes the best minimal-sample model as is: the selected
// model is re-estimated from all its inliers (the linear step of Hartley & Zisserman 2003, Alg.
// 11.4 / 4.2) while that does not lower its score. An 8-point F is very sensitive to pixel noise
// (in this module's tests a 0.7 px noise tilts the recovered rotation by ~1 degree, and then no
// essential-matrix solution passes the 2 px reprojection check); the refit removes that.
void RefineHomography(const Points& p1, const Points& p2, double inv_sigma2, Model* m) {
  Points n1, n2;
  const Eigen::Matrix3d T1 = Normalize(p1, &n1);
  const Eigen::Matrix3d T2 = Normalize(p2, &n2);
  for (int round = 0; round < 3; ++round) {
    const std::vector<size_t> inliers = Inliers(m->scored);
    if (inliers.size() < 8) return;
    const Eigen::Matrix3d H21 = T2.inverse() * ComputeH21(n1, n2, inliers) * T1;
    const Eigen::Matrix3d H12 = H21.inverse();
    if (!H12.allFinite()) return;
    Scored s = ScoreHomography(H21, H12, p1, p2, inv_sigma2);
    if (s.score < m->scored.score) return;
    *m = {H21, std::move(s)};
  }
}

void RefineFundamental(const Points& p1, const Points& p2, double inv_sigma2, Model* m) {
  Points n1, n2;
  const Eigen::Matrix3d T1 = Normalize(p1, &n1);
  const Eigen::Matrix3d T2 = Normalize(p2, &n2);
  for (int round = 0; round < 3; ++round) {
    const std::vector<size_t> inliers = Inliers(m->scored);
    if (inliers.size() < 8) return;
    const Eigen::Matrix3d F21 = T2.transpose() * ComputeF21(n1, n2, inliers) * T1;
    Scored s = ScoreFundamental(F21, p1, p2, inv_sigma2);
    if (s.score < m->scored.score) return;
    *m = {F21, std::move(s)};
  }
}

std::vector<Set8> RandomSets(size_t n, int iterations, uint32_t seed) {
  // ORB-SLAM2 draws 8 distinct indices per iteration.
  std::mt19937 rng(seed);
  std::vector<Set8> sets(static_cast<size_t>(iterations));
  std::vector<size_t> available;
  for (Set8& set : sets) {
    available.resize(n);
    std::iota(available.begin(), available.end(), size_t{0});
    for (size_t& idx : set) {
      std::uniform_int_distribution<size_t> pick(0, available.size() - 1);
      const size_t k = pick(rng);
      idx = available[k];
      available[k] = available.back();
      available.pop_back();
    }
  }
  return sets;
}

// Linear triangulation in camera 1 from normalized image coordinates (x1 = [I|0], x2 = [R|t]).
Eigen::Vector3d Triangulate(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2,
                            const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Matrix<double, 3, 4> P1 = Eigen::Matrix<double, 3, 4>::Zero();
  P1.leftCols<3>().setIdentity();
  Eigen::Matrix<double, 3, 4> P2;
  P2 << R, t;
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d X = svd.matrixV().col(3);
  return X.head<3>() / X(3);
}

struct Hypothesis {
  Eigen::Matrix3d R;
  Eigen::Vector3d t;
};

struct CheckedHypothesis {
  int num_good = 0;
  double parallax_deg = 0.0;
  std::vector<bool> good;
  std::vector<Eigen::Vector3d> points;
};

// ORB-SLAM2's CheckRT: triangulate every inlier; count those in front of both cameras (unless the
// rays are parallel) with reprojection error under th2 in both images; the parallax reported is
// that of the 50th-largest-parallax point, so a few far outliers cannot fake a wide baseline.
CheckedHypothesis CheckRT(const Hypothesis& h, const Points& p1, const Points& p2,
                          const std::vector<bool>& inlier, const Eigen::Matrix3d& K, double th2) {
  CheckedHypothesis c;
  c.good.assign(p1.size(), false);
  c.points.assign(p1.size(), Eigen::Vector3d::Zero());
  const Eigen::Matrix3d K_inv = K.inverse();
  const Eigen::Vector3d O2 = -h.R.transpose() * h.t;
  std::vector<double> cos_parallax;
  const auto reprojection2 = [&](const Eigen::Vector3d& pc, const Eigen::Vector2d& px) {
    return ((K * pc).hnormalized() - px).squaredNorm();
  };
  for (size_t i = 0; i < p1.size(); ++i) {
    if (!inlier[i]) continue;
    const Eigen::Vector2d x1 = (K_inv * p1[i].homogeneous()).head<2>();
    const Eigen::Vector2d x2 = (K_inv * p2[i].homogeneous()).head<2>();
    const Eigen::Vector3d X = Triangulate(x1, x2, h.R, h.t);
    if (!X.allFinite()) continue;
    const Eigen::Vector3d n1 = X, n2 = X - O2;
    const double cos_par = n1.dot(n2) / (n1.norm() * n2.norm());
    const Eigen::Vector3d X2 = h.R * X + h.t;
    if (X.z() <= 0.0 && cos_par < kParallelCos) continue;
    if (X2.z() <= 0.0 && cos_par < kParallelCos) continue;
    if (reprojection2(X, p1[i]) > th2 || reprojection2(X2, p2[i]) > th2) continue;
    cos_parallax.push_back(cos_par);
    c.points[i] = X;
    ++c.num_good;
    if (cos_par < kParallelCos) c.good[i] = true;
  }
  if (c.num_good > 0) {
    std::sort(cos_parallax.begin(), cos_parallax.end());
    const size_t idx = std::min<size_t>(50, cos_parallax.size() - 1);
    c.parallax_deg = std::acos(std::clamp(cos_parallax[idx], -1.0, 1.0)) * 180.0 / M_PI;
  }
  return c;
}

// Faugeras' decomposition of a calibrated homography into 8 (R, t) hypotheses (Faugeras & Lustman
// 1988), as ORB-SLAM2's ReconstructH. Empty when two singular values coincide (degenerate).
std::vector<Hypothesis> DecomposeHomography(const Eigen::Matrix3d& H21, const Eigen::Matrix3d& K) {
  const Eigen::Matrix3d A = K.inverse() * H21 * K;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(A, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU(), V = svd.matrixV();
  const Eigen::Matrix3d Vt = V.transpose();
  const double s = U.determinant() * Vt.determinant();
  const double d1 = svd.singularValues()(0), d2 = svd.singularValues()(1);
  const double d3 = svd.singularValues()(2);
  if (d1 / d2 < 1.00001 || d2 / d3 < 1.00001) return {};
  const double d1s = d1 * d1, d2s = d2 * d2, d3s = d3 * d3;
  const double aux1 = std::sqrt((d1s - d2s) / (d1s - d3s));
  const double aux3 = std::sqrt((d2s - d3s) / (d1s - d3s));
  const double x1[] = {aux1, aux1, -aux1, -aux1};
  const double x3[] = {aux3, -aux3, aux3, -aux3};
  std::vector<Hypothesis> out;
  // d' = d2
  const double st = std::sqrt((d1s - d2s) * (d2s - d3s)) / ((d1 + d3) * d2);
  const double ct = (d2s + d1 * d3) / ((d1 + d3) * d2);
  const double stheta[] = {st, -st, -st, st};
  for (int i = 0; i < 4; ++i) {
    Eigen::Matrix3d Rp = Eigen::Matrix3d::Identity();
    Rp(0, 0) = ct;
    Rp(0, 2) = -stheta[i];
    Rp(2, 0) = stheta[i];
    Rp(2, 2) = ct;
    const Eigen::Vector3d tp = Eigen::Vector3d(x1[i], 0.0, -x3[i]) * (d1 - d3);
    out.push_back({s * U * Rp * Vt, (U * tp).normalized()});
  }
  // d' = -d2
  const double sp = std::sqrt((d1s - d2s) * (d2s - d3s)) / ((d1 - d3) * d2);
  const double cp = (d1 * d3 - d2s) / ((d1 - d3) * d2);
  const double sphi[] = {sp, -sp, -sp, sp};
  for (int i = 0; i < 4; ++i) {
    Eigen::Matrix3d Rp = Eigen::Matrix3d::Identity();
    Rp(0, 0) = cp;
    Rp(0, 2) = sphi[i];
    Rp(1, 1) = -1.0;
    Rp(2, 0) = sphi[i];
    Rp(2, 2) = -cp;
    const Eigen::Vector3d tp = Eigen::Vector3d(x1[i], 0.0, x3[i]) * (d1 + d3);
    out.push_back({s * U * Rp * Vt, (U * tp).normalized()});
  }
  return out;
}

// E = K^T F K into its 4 (R, t) solutions (Hartley & Zisserman 2003, Sec. 9.6).
std::vector<Hypothesis> DecomposeEssential(const Eigen::Matrix3d& F21, const Eigen::Matrix3d& K) {
  const Eigen::Matrix3d E = K.transpose() * F21 * K;
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(E, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d U = svd.matrixU(), Vt = svd.matrixV().transpose();
  const Eigen::Vector3d t = U.col(2).normalized();
  Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
  W(0, 1) = -1.0;
  W(1, 0) = 1.0;
  W(2, 2) = 1.0;
  Eigen::Matrix3d R1 = U * W * Vt, R2 = U * W.transpose() * Vt;
  if (R1.determinant() < 0) R1 = -R1;
  if (R2.determinant() < 0) R2 = -R2;
  return {{R1, t}, {R2, t}, {R1, -t}, {R2, -t}};
}

int Count(const std::vector<bool>& v) {
  return static_cast<int>(std::count(v.begin(), v.end(), 1));
}

void Accept(const Hypothesis& h, CheckedHypothesis&& c, MonoInitialization* out) {
  out->ok = true;
  out->T_cam2_cam1 = geometry::SE3(h.R, h.t);
  out->parallax_deg = c.parallax_deg;
  out->triangulated = std::move(c.good);
  out->points_cam1 = std::move(c.points);
  out->num_triangulated = Count(out->triangulated);
}

// ORB-SLAM2's ReconstructH: best of 8 by good points, clearly ahead of the second best.
void ReconstructH(const Model& m, const Points& p1, const Points& p2, const Eigen::Matrix3d& K,
                  const MonoInitializerOptions& o, MonoInitialization* out) {
  const auto hypotheses = DecomposeHomography(m.M, K);
  if (hypotheses.empty()) {
    out->reason = "homography with repeated singular values (degenerate motion)";
    return;
  }
  const double th2 = 4.0 * o.sigma * o.sigma;
  int best = -1, best_good = 0, second_good = 0;
  std::vector<CheckedHypothesis> checked;
  for (size_t k = 0; k < hypotheses.size(); ++k) {
    checked.push_back(CheckRT(hypotheses[k], p1, p2, m.scored.inlier, K, th2));
    const int good = checked.back().num_good;
    if (good > best_good) {
      second_good = best_good;
      best_good = good;
      best = static_cast<int>(k);
    } else if (good > second_good) {
      second_good = good;
    }
  }
  const int n = out->num_inliers;
  if (best < 0 || second_good >= 0.75 * best_good) {
    out->reason = "no clear winner among the homography's 8 motions";
  } else if (checked[best].parallax_deg < o.min_parallax_deg) {
    out->reason = "too little parallax";
  } else if (best_good <= o.min_triangulated || best_good <= 0.9 * n) {
    out->reason = "too few points triangulated";
  } else {
    Accept(hypotheses[best], std::move(checked[best]), out);
  }
}

// ORB-SLAM2's ReconstructF: the 4 solutions of E; one must triangulate most inliers alone.
void ReconstructF(const Model& m, const Points& p1, const Points& p2, const Eigen::Matrix3d& K,
                  const MonoInitializerOptions& o, MonoInitialization* out) {
  const auto hypotheses = DecomposeEssential(m.M, K);
  const double th2 = 4.0 * o.sigma * o.sigma;
  std::vector<CheckedHypothesis> checked;
  int best = 0;
  for (size_t k = 0; k < hypotheses.size(); ++k) {
    checked.push_back(CheckRT(hypotheses[k], p1, p2, m.scored.inlier, K, th2));
    if (checked[k].num_good > checked[best].num_good) best = static_cast<int>(k);
  }
  const int max_good = checked[best].num_good;
  const int min_good = std::max(static_cast<int>(0.9 * out->num_inliers), o.min_triangulated);
  int similar = 0;
  for (const auto& c : checked) similar += c.num_good > 0.7 * max_good ? 1 : 0;
  if (max_good < min_good) {
    out->reason = "too few points triangulated";
  } else if (similar > 1) {
    out->reason = "no clear winner among the essential matrix's 4 motions";
  } else if (checked[best].parallax_deg <= o.min_parallax_deg) {
    out->reason = "too little parallax";
  } else {
    Accept(hypotheses[best], std::move(checked[best]), out);
  }
}

}  // namespace

void MonoInitializerOptions::Check() const {
  if (!(sigma > 0.0)) throw InputError("MonoInitializerOptions.sigma must be > 0");
  if (ransac_iterations < 1) {
    throw InputError("MonoInitializerOptions.ransac_iterations must be >= 1");
  }
  if (!(homography_ratio > 0.0 && homography_ratio < 1.0)) {
    throw InputError("MonoInitializerOptions.homography_ratio must be in (0, 1)");
  }
  if (!(min_parallax_deg >= 0.0)) {
    throw InputError("MonoInitializerOptions.min_parallax_deg must be >= 0");
  }
  if (min_triangulated < 1)
    throw InputError("MonoInitializerOptions.min_triangulated must be >= 1");
}

const char* ToString(TwoViewModel model) {
  switch (model) {
    case TwoViewModel::kHomography:
      return "homography";
    case TwoViewModel::kFundamental:
      return "fundamental";
    case TwoViewModel::kNone:
      break;
  }
  return "none";
}

MonoInitialization InitializeTwoView(const Points& p1, const Points& p2, const Eigen::Matrix3d& K,
                                     const MonoInitializerOptions& options) {
  options.Check();
  MOSLAM_CHECK(p1.size() == p2.size());
  MonoInitialization out;
  if (p1.size() < 8) {
    out.reason = "fewer than 8 correspondences";
    return out;
  }
  const std::vector<Set8> sets = RandomSets(p1.size(), options.ransac_iterations, options.seed);
  const double inv_sigma2 = 1.0 / (options.sigma * options.sigma);
  Model h, f;
  if (options.parallel) {
    auto future_f =
        std::async(std::launch::async, [&] { return FindFundamental(p1, p2, sets, inv_sigma2); });
    h = FindHomography(p1, p2, sets, inv_sigma2);
    f = future_f.get();
  } else {
    h = FindHomography(p1, p2, sets, inv_sigma2);
    f = FindFundamental(p1, p2, sets, inv_sigma2);
  }
  out.score_h = h.scored.score;
  out.score_f = f.scored.score;
  if (out.score_h + out.score_f <= 0.0) {
    out.reason = "no model explains the correspondences";
    return out;
  }
  out.ratio_h = out.score_h / (out.score_h + out.score_f);
  if (out.ratio_h > options.homography_ratio) {
    out.model = TwoViewModel::kHomography;
    RefineHomography(p1, p2, inv_sigma2, &h);
    out.num_inliers = Count(h.scored.inlier);
    ReconstructH(h, p1, p2, K, options, &out);
  } else {
    out.model = TwoViewModel::kFundamental;
    RefineFundamental(p1, p2, inv_sigma2, &f);
    out.num_inliers = Count(f.scored.inlier);
    ReconstructF(f, p1, p2, K, options, &out);
  }
  return out;
}

std::vector<int> SearchForInitialization(const feature::Frame& f1, const feature::Frame& f2,
                                         std::vector<Eigen::Vector2f>* prev_matched, float window,
                                         float ratio) {
  MOSLAM_CHECK(prev_matched->size() == f1.size());
  std::vector<int> matches12(f1.size(), -1), matches21(f2.size(), -1);
  std::vector<int> matched_distance(f2.size(), INT_MAX);
  for (size_t i1 = 0; i1 < f1.size(); ++i1) {
    const cv::KeyPoint& kp1 = f1.keypoints_undistorted[i1];
    if (kp1.octave > 0) continue;  // finest level only: best localized (ORB-SLAM2)
    const Eigen::Vector2f& prev = (*prev_matched)[i1];
    int best = INT_MAX, second = INT_MAX, best_i2 = -1;
    for (size_t i2 : f2.FeaturesInArea(prev.x(), prev.y(), window, 0, 0)) {
      const int dist = feature::DescriptorDistance(f1.descriptor(i1), f2.descriptor(i2));
      if (matched_distance[i2] <= dist) continue;
      if (dist < best) {
        second = best;
        best = dist;
        best_i2 = static_cast<int>(i2);
      } else if (dist < second) {
        second = dist;
      }
    }
    if (best_i2 < 0 || best > feature::kThLow) continue;
    if (!(static_cast<float>(best) < static_cast<float>(second) * ratio)) continue;
    if (matches21[best_i2] >= 0) matches12[matches21[best_i2]] = -1;
    matches12[i1] = best_i2;
    matches21[best_i2] = static_cast<int>(i1);
    matched_distance[best_i2] = best;
  }
  std::vector<size_t> which;
  std::vector<float> angles;
  for (size_t i1 = 0; i1 < f1.size(); ++i1) {
    if (matches12[i1] < 0) continue;
    which.push_back(i1);
    angles.push_back(f1.keypoints_undistorted[i1].angle -
                     f2.keypoints_undistorted[matches12[i1]].angle);
  }
  const std::vector<bool> keep = feature::RotationConsistent(angles);
  for (size_t k = 0; k < which.size(); ++k) {
    const size_t i1 = which[k];
    if (!keep[k]) {
      matches12[i1] = -1;
      continue;
    }
    const cv::Point2f& pt = f2.keypoints_undistorted[matches12[i1]].pt;
    (*prev_matched)[i1] = Eigen::Vector2f(pt.x, pt.y);
  }
  return matches12;
}

}  // namespace moslam::slam
