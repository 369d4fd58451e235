#include "moslam/slam/new_points.h"

#include <climits>
#include <cmath>
#include <optional>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/feature/matcher.h"
#include "moslam/geometry/triangulation.h"
#include "moslam/util/error.h"

namespace moslam::slam {

namespace {

Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d m;
  m << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return m;
}

// Fundamental matrix with x2^T F12 x1 = 0 for pixels x1 in kf1 and x2 in kf2 (ORB-SLAM2's
// ComputeF12, written with the transform from 1 to 2).
Eigen::Matrix3d Fundamental(const geometry::SE3& T_cam1_world, const geometry::SE3& T_cam2_world,
                            const Eigen::Matrix3d& K) {
  const geometry::SE3 T_21 = T_cam2_world * T_cam1_world.Inverse();
  const Eigen::Matrix3d E = Skew(T_21.translation()) * T_21.rotation_matrix();
  const Eigen::Matrix3d K_inv = K.inverse();
  return K_inv.transpose() * E * K_inv;
}

Eigen::Vector2d Normalized(const cv::KeyPoint& kp, const camera::PinholeCamera& cam) {
  return {(kp.pt.x - cam.cx()) / cam.fx(), (kp.pt.y - cam.cy()) / cam.fy()};
}

// Chi-square check of the reprojection of p_world into a keyframe's keypoint (mono: 2 DoF,
// stereo: 3 DoF), ORB-SLAM2's thresholds 5.991 and 7.8.
bool ReprojectionOk(const map::KeyFrame& kf, size_t i, const Eigen::Vector3d& p_world,
                    const camera::PinholeCamera& cam) {
  const Eigen::Vector3d p = kf.T_cam_world() * p_world;
  if (p.z() <= 0.0) return false;
  const cv::KeyPoint& kp = kf.frame.keypoints_undistorted[i];
  const double sigma2 = kf.frame.level_sigma2[kp.octave];
  const double u = cam.fx() * p.x() / p.z() + cam.cx();
  const double v = cam.fy() * p.y() / p.z() + cam.cy();
  const double ex = u - kp.pt.x, ey = v - kp.pt.y;
  const float ur = kf.frame.u_right[i];
  if (ur < 0.0f) return ex * ex + ey * ey <= 5.991 * sigma2;
  const double er = u - kf.frame.bf / p.z() - ur;
  return ex * ex + ey * ey + er * er <= 7.8 * sigma2;
}

double CosStereoParallax(const map::KeyFrame& kf, size_t i, const camera::PinholeCamera& cam) {
  const float depth = kf.frame.depth[i];
  if (kf.frame.u_right[i] < 0.0f || depth <= 0.0f) return 2.0;  // no stereo: sentinel
  const double baseline = kf.frame.bf / cam.fx();
  return std::cos(2.0 * std::atan2(baseline / 2.0, depth));
}

std::optional<Eigen::Vector3d> Unproject(const map::KeyFrame& kf, size_t i,
                                         const camera::PinholeCamera& cam) {
  auto p = kf.frame.UnprojectCamera(i, cam);
  if (!p) return std::nullopt;
  return kf.T_world_cam() * *p;
}

// ORB-SLAM2's choice: triangulate when the rays' parallax exceeds both stereo parallaxes (and is
// not tiny without stereo); otherwise back-project the view with the larger stereo parallax.
std::optional<Eigen::Vector3d> Triangulate(const map::KeyFrame& kf1, size_t i1,
                                           const map::KeyFrame& kf2, size_t i2,
                                           const camera::PinholeCamera& cam) {
  const Eigen::Vector2d x1 = Normalized(kf1.frame.keypoints_undistorted[i1], cam);
  const Eigen::Vector2d x2 = Normalized(kf2.frame.keypoints_undistorted[i2], cam);
  const Eigen::Vector3d ray1 = kf1.T_world_cam().rotation() * x1.homogeneous();
  const Eigen::Vector3d ray2 = kf2.T_world_cam().rotation() * x2.homogeneous();
  const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());
  const double cos_stereo1 = CosStereoParallax(kf1, i1, cam);
  const double cos_stereo2 = CosStereoParallax(kf2, i2, cam);
  const double cos_stereo = std::min(cos_stereo1, cos_stereo2);
  const bool stereo = cos_stereo1 < 2.0 || cos_stereo2 < 2.0;
  if (cos_rays < cos_stereo && cos_rays > 0.0 && (stereo || cos_rays < 0.9998)) {
    return geometry::TriangulateDlt(x1, kf1.T_cam_world(), x2, kf2.T_cam_world());
  }
  if (cos_stereo1 < 2.0 && cos_stereo1 < cos_stereo2) return Unproject(kf1, i1, cam);
  if (cos_stereo2 < 2.0 && cos_stereo2 < cos_stereo1) return Unproject(kf2, i2, cam);
  return std::nullopt;
}

bool ScaleConsistent(const map::KeyFrame& kf1, size_t i1, const map::KeyFrame& kf2, size_t i2,
                     const Eigen::Vector3d& p) {
  const double dist1 = (p - kf1.CameraCenter()).norm();
  const double dist2 = (p - kf2.CameraCenter()).norm();
  if (dist1 == 0.0 || dist2 == 0.0) return false;
  const double ratio_dist = dist2 / dist1;
  const double ratio_octave = kf1.frame.scale_factors[kf1.frame.keypoints_undistorted[i1].octave] /
                              kf2.frame.scale_factors[kf2.frame.keypoints_undistorted[i2].octave];
  const double factor = 1.5 * kf1.frame.scale_factors.at(std::min(1, kf1.frame.num_levels() - 1));
  return !(ratio_dist * factor < ratio_octave || ratio_dist > ratio_octave * factor);
}

}  // namespace

void NewPointsOptions::Check() const {
  if (num_neighbours < 1) throw InputError("NewPointsOptions.num_neighbours must be >= 1");
}

namespace {
// The epipolar band of SearchForTriangulation over a frame's keypoints: within 3.84 sigma^2 of
// a line (chi-square, 1 DoF, 95 %) at the keypoint's pyramid level. The keypoints are laid out as
// plain arrays: run pair by pair on the keypoint structs inside the search, this test over every
// pair of keypoints was a third of a deterministic stereo KITTI 06 run's CPU (perf, 2026-12-07);
// over arrays the whole search takes 40 % less (2.7 -> 1.6 s of CPU in that run, the same
// matches).
class EpipolarBand {
 public:
  explicit EpipolarBand(const feature::Frame& frame) {
    const auto& kps = frame.keypoints_undistorted;
    x_.resize(kps.size());
    y_.resize(kps.size());
    band_.resize(kps.size());
    for (size_t i = 0; i < kps.size(); ++i) {
      x_[i] = kps[i].pt.x;
      y_[i] = kps[i].pt.y;
      band_[i] = 3.84 * frame.level_sigma2[kps[i].octave];
    }
    within_.reserve(kps.size());
  }

  // Every keypoint within the band of `line` (a x + b y + c = 0), in index order; valid until the
  // next call.
  const std::vector<size_t>& Within(const Eigen::Vector3d& line) {
    within_.clear();
    const double line_norm2 = line.x() * line.x() + line.y() * line.y();
    if (line_norm2 == 0.0) return within_;
    for (size_t i = 0; i < x_.size(); ++i) {
      if (Inside(i, line, line_norm2)) within_.push_back(i);
    }
    return within_;
  }
  // The same among `candidates`, in their order.
  template <class Indices>
  const std::vector<size_t>& Within(const Eigen::Vector3d& line, const Indices& candidates) {
    within_.clear();
    const double line_norm2 = line.x() * line.x() + line.y() * line.y();
    if (line_norm2 == 0.0) return within_;
    for (const size_t i : candidates) {
      if (Inside(i, line, line_norm2)) within_.push_back(i);
    }
    return within_;
  }

 private:
  bool Inside(size_t i, const Eigen::Vector3d& line, double line_norm2) const {
    const double num = line.x() * x_[i] + line.y() * y_[i] + line.z();
    return num * num < band_[i] * line_norm2;
  }

  std::vector<double> x_, y_, band_;
  std::vector<size_t> within_;
};
}  // namespace

std::vector<std::pair<size_t, size_t>> SearchForTriangulation(
    const feature::Frame& frame1, const geometry::SE3& T_cam1_world, const std::vector<bool>& free1,
    const feature::Frame& frame2, const geometry::SE3& T_cam2_world,
    const std::vector<bool>& free2_mask, const camera::PinholeCamera& cam,
    const vocab::FeatureVector* features1, const vocab::FeatureVector* features2) {
  const Eigen::Matrix3d F = Fundamental(T_cam1_world, T_cam2_world, cam.K());
  const auto& kps1 = frame1.keypoints_undistorted;
  const auto& kps2 = frame2.keypoints_undistorted;
  // Monocular pairs: keypoints of frame2 near the epipole (where frame1's centre projects) are
  // skipped: their rays are nearly parallel to the baseline, so depth is ill-conditioned
  // (ORB-SLAM2's SearchForTriangulation, which tests it for keypoints without stereo; applied here
  // only between monocular frames so stereo / RGB-D results are unchanged).
  const bool mono_pair = frame1.bf <= 0.0 && frame2.bf <= 0.0;
  const Eigen::Vector3d c1_in_2 = T_cam2_world * T_cam1_world.Inverse().translation();
  const bool epipole_visible = mono_pair && c1_in_2.z() > 0.0;
  const Eigen::Vector2d epipole = epipole_visible
                                      ? Eigen::Vector2d((cam.K() * c1_in_2).hnormalized())
                                      : Eigen::Vector2d::Zero();
  std::vector<bool> used2(kps2.size(), false);
  std::vector<std::pair<size_t, size_t>> matches;
  std::vector<float> angles;
  EpipolarBand band(frame2);
  const auto epipolar_line = [&](size_t i1) {
    return Eigen::Vector3d(F * Eigen::Vector3d(kps1[i1].pt.x, kps1[i1].pt.y, 1.0));
  };
  // Best free, unused keypoint of frame2 among `in_band` (the candidates within the epipolar band
  // of keypoint i1, EpipolarBand) for i1: descriptor distance <= kThLow, off the epipole.
  const auto match_one = [&](size_t i1, const std::vector<size_t>& in_band) {
    int best_dist = feature::kThLow + 1;
    int best_i2 = -1;
    for (const size_t i2 : in_band) {
      if (!free2_mask[i2] || used2[i2]) continue;
      const Eigen::Vector2d x2(kps2[i2].pt.x, kps2[i2].pt.y);
      if (epipole_visible &&
          (x2 - epipole).squaredNorm() < 100.0 * frame2.scale_factors[kps2[i2].octave]) {
        continue;
      }
      const int dist = feature::DescriptorDistance(frame1.descriptor(i1), frame2.descriptor(i2));
      if (dist >= best_dist) continue;
      best_dist = dist;
      best_i2 = static_cast<int>(i2);
    }
    if (best_i2 < 0) return;
    used2[best_i2] = true;
    matches.emplace_back(i1, static_cast<size_t>(best_i2));
    angles.push_back(kps1[i1].angle - kps2[best_i2].angle);
  };
  // ORB-SLAM2's SearchForTriangulation compares only keypoints under the same vocabulary node
  // (the direct index), which cuts the candidates by roughly the number of nodes: the
  // brute-force search below was 38 % of all CPU time of a monocular KITTI run, where 20
  // neighbours are searched and mapping time decides how often local BA is interrupted. Only
  // for monocular pairs: with stereo/RGB-D the node restriction left maps sparse enough to lose
  // the synthetic relocalization test's camera again, and their search (10 neighbours, close
  // points made at keyframe creation) is cheaper anyway.
  if (mono_pair && features1 && features2 && !features1->empty() && !features2->empty()) {
    auto it1 = features1->begin();
    auto it2 = features2->begin();
    while (it1 != features1->end() && it2 != features2->end()) {
      if (it1->first < it2->first) {
        it1 = features1->lower_bound(it2->first);
      } else if (it2->first < it1->first) {
        it2 = features2->lower_bound(it1->first);
      } else {
        for (const uint32_t i1 : it1->second) {
          if (free1[i1]) match_one(i1, band.Within(epipolar_line(i1), it2->second));
        }
        ++it1;
        ++it2;
      }
    }
  } else {
    for (size_t i1 = 0; i1 < kps1.size(); ++i1) {
      if (free1[i1]) match_one(i1, band.Within(epipolar_line(i1)));
    }
  }
  const std::vector<bool> keep = feature::RotationConsistent(angles);
  std::vector<std::pair<size_t, size_t>> out;
  for (size_t k = 0; k < matches.size(); ++k) {
    if (keep[k]) out.push_back(matches[k]);
  }
  return out;
}

namespace {
// Keypoints that may seed a new point: no (good) point yet, not at a movable mask's border
// (feature::Frame::near_movable: where a network is least sure of a body's extent) and not seen
// moving (feature::Frame::moving).
std::vector<bool> FreeSlots(const map::KeyFrame& kf) {
  std::vector<bool> free(kf.points.size());
  for (size_t i = 0; i < free.size(); ++i) {
    free[i] = (!kf.points[i] || kf.points[i]->bad) && !kf.frame.SeedsNoPoint(i);
  }
  return free;
}
}  // namespace

std::vector<std::pair<size_t, size_t>> SearchForTriangulation(const map::KeyFrame& kf1,
                                                              const map::KeyFrame& kf2,
                                                              const camera::PinholeCamera& cam) {
  return SearchForTriangulation(kf1.frame, kf1.T_cam_world(), FreeSlots(kf1), kf2.frame,
                                kf2.T_cam_world(), FreeSlots(kf2), cam, &kf1.bow_features,
                                &kf2.bow_features);
}

TriangulationSearch PrepareTriangulationSearch(const std::shared_ptr<map::KeyFrame>& kf,
                                               const camera::PinholeCamera& cam,
                                               const NewPointsOptions& options) {
  options.Check();
  TriangulationSearch search;
  search.kf = kf;
  search.T_cam_world = kf->T_cam_world();
  search.free = FreeSlots(*kf);
  const double stereo_baseline = cam.fx() > 0.0 ? kf->frame.bf / cam.fx() : 0.0;
  for (const auto& kf2 : kf->BestCovisibles(options.num_neighbours)) {
    // Too short a baseline adds nothing over the stereo depth (ORB-SLAM2).
    const double baseline = (kf2->CameraCenter() - kf->CameraCenter()).norm();
    if (stereo_baseline > 0.0 && baseline < stereo_baseline) continue;
    // Monocular: a baseline under 1 % of the neighbour's median scene depth triangulates nothing
    // reliable (ORB-SLAM2's ratioBaselineDepth).
    if (stereo_baseline <= 0.0) {
      const double median_depth = kf2->MedianDepth();
      if (median_depth <= 0.0 || baseline / median_depth < 0.01) continue;
    }
    search.neighbours.push_back({kf2, kf2->T_cam_world(), FreeSlots(*kf2), {}});
  }
  return search;
}

void RunTriangulationSearch(TriangulationSearch* search, const camera::PinholeCamera& cam) {
  for (auto& n : search->neighbours) {
    n.matches = SearchForTriangulation(search->kf->frame, search->T_cam_world, search->free,
                                       n.kf->frame, n.T_cam_world, n.free, cam,
                                       &search->kf->bow_features, &n.kf->bow_features);
  }
}

std::vector<std::shared_ptr<map::MapPoint>> CreatePointsFromMatches(
    map::Map* map, const TriangulationSearch& search, const camera::PinholeCamera& cam) {
  std::vector<std::shared_ptr<map::MapPoint>> created;
  const auto& kf = search.kf;
  if (kf->bad()) return created;
  for (const auto& n : search.neighbours) {
    const auto& kf2 = n.kf;
    if (kf2->bad()) continue;
    for (const auto& [i1, i2] : n.matches) {
      // Slots may have been filled since the snapshot (fusion, tracking): re-checked here.
      if (kf->points[i1] || kf2->points[i2]) continue;
      const auto p = Triangulate(*kf, i1, *kf2, i2, cam);
      if (!p || !p->allFinite()) continue;
      if (!ReprojectionOk(*kf, i1, *p, cam) || !ReprojectionOk(*kf2, i2, *p, cam)) continue;
      if (!ScaleConsistent(*kf, i1, *kf2, i2, *p)) continue;
      auto point = map->CreateMapPoint(*p, kf);
      point->AddObservation(kf, i1);
      point->AddObservation(kf2, i2);
      kf->points[i1] = point;
      kf2->points[i2] = point;
      point->ComputeDistinctiveDescriptor();
      point->UpdateNormalAndDepth();
      created.push_back(point);
    }
  }
  return created;
}

std::vector<std::shared_ptr<map::MapPoint>> CreateNewMapPoints(
    map::Map* map, const std::shared_ptr<map::KeyFrame>& kf, const camera::PinholeCamera& cam,
    const NewPointsOptions& options) {
  TriangulationSearch search = PrepareTriangulationSearch(kf, cam, options);
  RunTriangulationSearch(&search, cam);
  return CreatePointsFromMatches(map, search, cam);
}

}  // namespace moslam::slam
