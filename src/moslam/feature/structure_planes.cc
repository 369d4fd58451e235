#include "moslam/feature/structure_planes.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::feature {

void StructurePlaneOptions::Check() const {
  if (grid_px < 1) throw InputError("StructurePlaneOptions.grid_px must be >= 1");
  if (max_planes < 0 || max_planes > 8) {
    throw InputError("StructurePlaneOptions.max_planes must be in 0..8");
  }
  if (iterations < 1) throw InputError("StructurePlaneOptions.iterations must be >= 1");
  if (score_stride < 1) throw InputError("StructurePlaneOptions.score_stride must be >= 1");
  if (!(inlier_abs >= 0.0) || !(inlier_rel >= 0.0) || !(inlier_abs + inlier_rel > 0.0)) {
    throw InputError("StructurePlaneOptions.inlier_abs and inlier_rel must be >= 0, not both 0");
  }
  if (!(min_share >= 0.0 && min_share <= 1.0)) {
    throw InputError("StructurePlaneOptions.min_share must be in [0, 1]");
  }
  if (!(min_side_m >= 0.0)) throw InputError("StructurePlaneOptions.min_side_m must be >= 0");
}

namespace {

struct Sample {
  Eigen::Vector3d p;
  cv::Point cell;
};

// Whether p lies on the plane within the inlier distance, which grows with depth as its noise.
bool OnPlane(const Eigen::Vector4d& plane, const Eigen::Vector3d& p,
             const StructurePlaneOptions& o) {
  return std::abs(plane.head<3>().dot(p) + plane[3]) < o.inlier_abs + o.inlier_rel * p.z();
}

// Samples on the plane among `points`, or any number <= `beat` as soon as more than `beat`
// cannot be reached (a hypothesis only counts when it beats the best so far, so the rest of a
// losing one need not be counted: the winner is the same, at about half the work).
int Support(const Eigen::Vector4d& plane, const std::vector<Eigen::Vector3d>& points,
            const StructurePlaneOptions& o, int beat) {
  int count = 0;
  const int n = static_cast<int>(points.size());
  for (int k = 0; k < n; ++k) {
    count += OnPlane(plane, points[k], o);
    if ((k & 63) == 63 && count + (n - 1 - k) <= beat) return count;
  }
  return count;
}

// The plane through the most of `open` (indices into samples), or a zero vector. Hypotheses are
// scored on every score_stride-th sample only (a regular subset of the grid: the ranking of large
// planes does not change, the cost falls by the stride), the winner's support on all of them.
Eigen::Vector4d BestPlane(const std::vector<Sample>& samples, const std::vector<int>& open,
                          const StructurePlaneOptions& o, std::mt19937* rng, int* support) {
  std::uniform_int_distribution<size_t> pick(0, open.size() - 1);
  // The scored samples, contiguous (no index to follow per test).
  std::vector<Eigen::Vector3d> scored, all;
  scored.reserve(open.size() / o.score_stride + 1);
  all.reserve(open.size());
  for (size_t k = 0; k < open.size(); ++k) {
    all.push_back(samples[open[k]].p);
    if (k % o.score_stride == 0) scored.push_back(samples[open[k]].p);
  }
  Eigen::Vector4d best = Eigen::Vector4d::Zero();
  int best_score = 0;
  for (int it = 0; it < o.iterations; ++it) {
    const Eigen::Vector3d& a = samples[open[pick(*rng)]].p;
    const Eigen::Vector3d& b = samples[open[pick(*rng)]].p;
    const Eigen::Vector3d& c = samples[open[pick(*rng)]].p;
    Eigen::Vector3d n = (b - a).cross(c - a);
    if (n.norm() < 1e-9) continue;
    n.normalize();
    const Eigen::Vector4d plane(n.x(), n.y(), n.z(), -n.dot(a));
    const int score = Support(plane, scored, o, best_score);
    if (score > best_score) {
      best_score = score;
      best = plane;
    }
  }
  *support = best_score > 0 ? Support(best, all, o, -1) : 0;
  return best;
}

// Second principal extent (metres) of the samples in `part`: sqrt(12 var) is the side of the
// uniform rectangle with that variance.
double SecondSide(const std::vector<Sample>& samples, const std::vector<int>& part) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (int i : part) mean += samples[i].p;
  mean /= static_cast<double>(part.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int i : part) {
    const Eigen::Vector3d q = samples[i].p - mean;
    cov += q * q.transpose();
  }
  cov /= static_cast<double>(part.size());
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  return std::sqrt(12.0 * std::max(0.0, eig.eigenvalues()[1]));  // ascending: [1] is the middle
}

}  // namespace

StructurePlanes StructurePlanes::Find(const cv::Mat& depth, const camera::PinholeCamera& camera,
                                      const cv::Mat& exclude,
                                      const StructurePlaneOptions& options) {
  options.Check();
  MOSLAM_CHECK(depth.type() == CV_32FC1);
  MOSLAM_CHECK(exclude.empty() || (exclude.type() == CV_8UC1 && exclude.size() == depth.size()));
  StructurePlanes out(camera, options);
  const int g = options.grid_px, gw = depth.cols / g, gh = depth.rows / g;
  std::vector<Sample> samples;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const int u = i * g + g / 2, v = j * g + g / 2;
      const float z = depth.at<float>(v, u);
      if (!(z > 0.0f) || !std::isfinite(z)) continue;
      if (!exclude.empty() && exclude.at<uint8_t>(v, u) != 0) continue;
      samples.push_back({out.Point(u, v, z), cv::Point(i, j)});
    }
  }
  const double min_count = options.min_share * static_cast<double>(samples.size());
  std::vector<char> used(samples.size(), 0);
  std::mt19937 rng(options.seed);
  for (int k = 0; k < options.max_planes; ++k) {
    std::vector<int> open;
    for (size_t i = 0; i < samples.size(); ++i) {
      if (!used[i]) open.push_back(static_cast<int>(i));
    }
    if (open.size() < 3) break;
    int support = 0;
    const Eigen::Vector4d plane = BestPlane(samples, open, options, &rng, &support);
    if (support == 0 || support < min_count) break;
    // The largest 4-connected part of the inliers on the grid: one surface, not every sample
    // that a slab through the room happens to cut.
    cv::Mat inliers = cv::Mat::zeros(gh, gw, CV_8UC1);
    for (int i : open) {
      if (OnPlane(plane, samples[i].p, options)) inliers.at<uint8_t>(samples[i].cell) = 255;
    }
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(inliers, labels, stats, centroids, 4);
    int largest = 0, area = 0;
    for (int l = 1; l < n; ++l) {
      if (stats.at<int>(l, cv::CC_STAT_AREA) > area) {
        area = stats.at<int>(l, cv::CC_STAT_AREA);
        largest = l;
      }
    }
    if (largest == 0) break;
    std::vector<int> part;
    for (int i : open) {
      if (labels.at<int>(samples[i].cell) != largest) continue;
      part.push_back(i);
      used[i] = 1;
    }
    if (area < min_count || SecondSide(samples, part) < options.min_side_m) continue;
    cv::Mat cells = labels == largest;
    cv::dilate(cells, cells, cv::Mat::ones(3, 3, CV_8UC1));
    out.planes_.push_back({plane, cells});
  }
  // Which planes' parts cover each cell, one bit per plane (max_planes <= 8): Contains() tests
  // the planes of a pixel's cell only, and most cells have none.
  out.cell_planes_ = cv::Mat::zeros(std::max(gh, 1), std::max(gw, 1), CV_8UC1);
  for (size_t k = 0; k < out.planes_.size(); ++k) {
    const cv::Mat& cells = out.planes_[k].cells;
    for (int j = 0; j < cells.rows; ++j) {
      const auto* c = cells.ptr<uint8_t>(j);
      auto* bits = out.cell_planes_.ptr<uint8_t>(j);
      for (int i = 0; i < cells.cols; ++i) {
        if (c[i] != 0) bits[i] |= static_cast<uint8_t>(1u << k);
      }
    }
  }
  return out;
}

Eigen::Vector3d StructurePlanes::Point(int u, int v, float z) const {
  return static_cast<double>(z) * camera_.UnprojectPinhole(Eigen::Vector2d(u, v));
}

bool StructurePlanes::Contains(int u, int v, float z) const {
  if (planes_.empty() || !(z > 0.0f) || !std::isfinite(z)) return false;
  const int g = options_.grid_px;
  const int i = std::min(u / g, cell_planes_.cols - 1), j = std::min(v / g, cell_planes_.rows - 1);
  if (i < 0 || j < 0) return false;
  const unsigned bits = cell_planes_.at<uint8_t>(j, i);
  if (bits == 0) return false;
  const Eigen::Vector3d p = Point(u, v, z);
  for (size_t k = 0; k < planes_.size(); ++k) {
    if (((bits >> k) & 1u) != 0 && OnPlane(planes_[k].coefficients, p, options_)) return true;
  }
  return false;
}

}  // namespace moslam::feature
