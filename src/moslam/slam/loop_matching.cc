#include "moslam/slam/loop_matching.h"

#include <climits>
#include <cmath>
#include <set>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/feature/matcher.h"
#include "moslam/map/map_point.h"
#include "moslam/util/check.h"

namespace moslam::slam {
namespace {

// The keypoint of `kf` nearest in descriptor to `point` around the projection of the camera-frame
// position p_cam (the point's distance from the camera is |p_cam| / scale_to_point_units), on the
// predicted level or the one below; -1 when none or the projection falls outside. `taken` (may be
// null) marks keypoints that may not be used.
int BestNearProjection(const map::KeyFrame& kf, const map::MapPoint& point,
                       const Eigen::Vector3d& p_cam, double distance,
                       const camera::PinholeCamera& cam, float radius_px, int max_distance,
                       const PointMatches* taken) {
  if (p_cam.z() <= 0.0 || point.descriptor.empty()) return -1;
  const double u = cam.fx() * p_cam.x() / p_cam.z() + cam.cx();
  const double v = cam.fy() * p_cam.y() / p_cam.z() + cam.cy();
  const auto& b = kf.frame.bounds;
  if (u < b.min_x || u > b.max_x || v < b.min_y || v > b.max_y) return -1;
  if (distance < 0.8 * point.min_distance || distance > 1.2 * point.max_distance) return -1;
  const int num_levels = kf.frame.num_levels();
  const float log_scale = std::log(kf.frame.scale_factors.at(std::min(1, num_levels - 1)));
  const int level = point.PredictScale(static_cast<float>(distance), log_scale, num_levels);
  const float radius = radius_px * kf.frame.scale_factors[level];
  int best_dist = INT_MAX, best = -1;
  for (size_t i : kf.frame.FeaturesInArea(static_cast<float>(u), static_cast<float>(v), radius)) {
    const int octave = kf.frame.keypoints_undistorted[i].octave;
    if (octave < level - 1 || octave > level) continue;
    if (taken && (*taken)[i]) continue;
    const int d =
        feature::DescriptorDistance(point.descriptor.ptr<uint8_t>(), kf.frame.descriptor(i));
    if (d < best_dist) best_dist = d, best = static_cast<int>(i);
  }
  return best_dist <= max_distance ? best : -1;
}

}  // namespace

PointMatches MatchKeyFramePoints(const map::KeyFrame& kf1, const map::KeyFrame& kf2, float ratio) {
  PointMatches out(kf1.points.size());
  auto collect = [](const map::KeyFrame& kf, std::vector<cv::KeyPoint>* kps, cv::Mat* desc,
                    std::vector<size_t>* index) {
    for (size_t i = 0; i < kf.points.size(); ++i) {
      if (!kf.points[i] || kf.points[i]->bad) continue;
      kps->push_back(kf.frame.keypoints_undistorted[i]);
      desc->push_back(kf.frame.descriptors.row(static_cast<int>(i)));
      index->push_back(i);
    }
  };
  std::vector<cv::KeyPoint> kp1, kp2;
  cv::Mat d1, d2;
  std::vector<size_t> i1, i2;
  collect(kf1, &kp1, &d1, &i1);
  collect(kf2, &kp2, &d2, &i2);
  if (kp1.empty() || kp2.empty()) return out;
  feature::DescriptorMatchOptions options;
  options.ratio = ratio;
  for (const auto& m : feature::MatchByDescriptor(kp1, d1, kp2, d2, options)) {
    const auto& p2 = kf2.points[i2[static_cast<size_t>(m.index2)]];
    out[i1[static_cast<size_t>(m.index1)]] = p2;
  }
  return out;
}

int SearchBySim3(const map::KeyFrame& kf1, const map::KeyFrame& kf2, const geometry::Sim3& S_12,
                 const camera::PinholeCamera& camera, float radius_px, PointMatches* matches) {
  MOSLAM_CHECK_EQ(matches->size(), kf1.points.size());
  const geometry::Sim3 S_21 = S_12.Inverse();
  const geometry::Sim3 S_1w(kf1.T_cam_world());
  const geometry::Sim3 S_2w(kf2.T_cam_world());
  // Points of kf2 already matched from kf1 are not searched again.
  std::set<const map::MapPoint*> already;
  for (const auto& p : *matches) {
    if (p) already.insert(p.get());
  }
  // kf1's points into kf2: camera-2 coordinates S_21 * (T_1w X); distances are in camera 2's
  // units, which are the map's for the point's scale range (scale 1 for stereo/RGB-D).
  std::vector<int> match12(kf1.points.size(), -1);
  for (size_t i = 0; i < kf1.points.size(); ++i) {
    const auto& p = kf1.points[i];
    if (!p || p->bad || (*matches)[i]) continue;
    const Eigen::Vector3d p2 = S_21 * (S_1w * p->position);
    match12[i] =
        BestNearProjection(kf2, *p, p2, p2.norm(), camera, radius_px, feature::kThHigh, nullptr);
  }
  std::vector<int> match21(kf2.points.size(), -1);
  for (size_t i = 0; i < kf2.points.size(); ++i) {
    const auto& p = kf2.points[i];
    if (!p || p->bad || already.count(p.get())) continue;
    const Eigen::Vector3d p1 = S_12 * (S_2w * p->position);
    match21[i] =
        BestNearProjection(kf1, *p, p1, p1.norm(), camera, radius_px, feature::kThHigh, nullptr);
  }
  int added = 0;
  for (size_t i = 0; i < match12.size(); ++i) {
    const int j = match12[i];
    if (j < 0 || match21[static_cast<size_t>(j)] != static_cast<int>(i)) continue;
    (*matches)[i] = kf2.points[static_cast<size_t>(j)];
    ++added;
  }
  return added;
}

int SearchByProjectionSim3(const map::KeyFrame& kf, const geometry::Sim3& S_cam_world,
                           const std::vector<std::shared_ptr<map::MapPoint>>& points,
                           const camera::PinholeCamera& camera, float radius_px,
                           PointMatches* matched) {
  MOSLAM_CHECK_EQ(matched->size(), kf.points.size());
  // The pose with the scale applied: same projection, metric distances of this camera.
  const double s = S_cam_world.scale();
  const geometry::SE3 T_cw(S_cam_world.rotation(), S_cam_world.translation() / s);
  const Eigen::Vector3d center = T_cw.Inverse().translation();
  std::set<const map::MapPoint*> already;
  for (const auto& p : *matched) {
    if (p) already.insert(p.get());
  }
  int added = 0;
  for (const auto& p : points) {
    if (!p || p->bad || already.count(p.get())) continue;
    const Eigen::Vector3d po = p->position - center;
    const double dist = po.norm();
    if (po.dot(p->normal) < 0.5 * dist) continue;  // more than 60 degrees off its mean view
    const int i = BestNearProjection(kf, *p, T_cw * p->position, dist, camera, radius_px,
                                     feature::kThLow, matched);
    if (i < 0) continue;
    (*matched)[static_cast<size_t>(i)] = p;
    already.insert(p.get());
    ++added;
  }
  return added;
}

}  // namespace moslam::slam
