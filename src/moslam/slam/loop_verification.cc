#include "moslam/slam/loop_verification.h"

#include <algorithm>
#include <cmath>
#include <set>

#include "moslam/geometry/so3.h"
#include "moslam/slam/loop_matching.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void LoopVerificationOptions::Check() const {
  auto non_negative = [](double v, const char* name) {
    if (!(v >= 0.0)) ThrowInput("LoopVerificationOptions.{} must be >= 0 (got {})", name, v);
  };
  non_negative(max_drift_ratio, "max_drift_ratio");
  non_negative(max_drift_floor_m, "max_drift_floor_m");
  non_negative(max_rotation_ratio, "max_rotation_ratio");
  non_negative(max_rotation_floor_deg, "max_rotation_floor_deg");
  non_negative(max_log_scale, "max_log_scale");
  non_negative(min_revisit_ratio, "min_revisit_ratio");
  non_negative(depth_tolerance_ratio, "depth_tolerance_ratio");
  if (!(min_depth_consistent >= 0.0 && min_depth_consistent <= 1.0)) {
    ThrowInput("LoopVerificationOptions.min_depth_consistent must be in [0, 1] (got {})",
               min_depth_consistent);
  }
  if (min_depth_samples < 1) ThrowInput("LoopVerificationOptions.min_depth_samples must be >= 1");
  if (neighbours < 0) ThrowInput("LoopVerificationOptions.neighbours must be >= 0");
  if (min_neighbour_matches < 1) {
    ThrowInput("LoopVerificationOptions.min_neighbour_matches must be >= 1");
  }
  if (min_neighbours_passing < 0) {
    ThrowInput("LoopVerificationOptions.min_neighbours_passing must be >= 0");
  }
  if (spread_cols < 1 || spread_rows < 1) {
    ThrowInput("LoopVerificationOptions.spread_cols and spread_rows must be >= 1");
  }
  if (min_spread_cells < 0 || min_spread_cells > spread_cols * spread_rows) {
    ThrowInput("LoopVerificationOptions.min_spread_cells must be in [0, {}] (got {})",
               spread_cols * spread_rows, min_spread_cells);
  }
}

namespace {

using KeyFramePtr = std::shared_ptr<map::KeyFrame>;

constexpr double kRadToDeg = 180.0 / M_PI;
// Radius (pixels at level 0) of the neighbours' projection search: ORB-SLAM2's loop-side radius.
constexpr float kNeighbourRadius = 10.0f;

// The metric pose of a corrected camera: Sim(3) S_cam_world with its scale taken out of the
// translation (same projection; distances in the camera's own units).
geometry::SE3 MetricPose(const geometry::Sim3& S_cam_world) {
  return geometry::SE3(S_cam_world.rotation(), S_cam_world.translation() / S_cam_world.scale());
}

// What the odometry says about the loop: the correction it asks of the current keyframe, the
// way travelled since the loop keyframe and the straight distance between the two. Rules 1 and
// 1b compare these; the caller also ranks verified loops by the correction.
void Measure(const map::Map& map, const DetectedLoop& loop, LoopVerification* v) {
  const map::KeyFrame& cur = *loop.current;
  const geometry::SE3 T_world_corrected = MetricPose(loop.S_cur_world).Inverse();
  v->correction_m = (T_world_corrected.translation() - cur.CameraCenter()).norm();
  v->correction_deg =
      geometry::RotationAngle(T_world_corrected.rotation() * cur.T_cam_world().rotation()) *
      kRadToDeg;
  v->log_scale = std::log(loop.S_cur_world.scale());
  PathLength(map, loop.loop->id, cur.id, &v->path_m, &v->path_deg);
  v->displacement_m = (cur.CameraCenter() - loop.loop->CameraCenter()).norm();
}

// Rule 1: the correction against the odometry's possible drift.
bool DriftHolds(const LoopVerificationOptions& o, LoopVerification* v) {
  if (!o.check_drift) return true;
  if (v->correction_m > o.max_drift_floor_m + o.max_drift_ratio * v->path_m) {
    v->rejected_by = "drift";
    return false;
  }
  if (v->correction_deg > o.max_rotation_floor_deg + o.max_rotation_ratio * v->path_deg) {
    v->rejected_by = "rotation";
    return false;
  }
  if (o.max_log_scale > 0.0 && std::abs(v->log_scale) > o.max_log_scale) {
    v->rejected_by = "scale";
    return false;
  }
  return true;
}

// Rule 1b: the path since the loop keyframe came back, it did not just go on.
bool RevisitHolds(const LoopVerificationOptions& o, LoopVerification* v) {
  if (!o.check_revisit || o.min_revisit_ratio <= 0.0) return true;
  if (v->path_m < o.min_revisit_ratio * v->displacement_m) {
    v->rejected_by = "revisit";
    return false;
  }
  return true;
}

// Rule 2: loop-side points at the depths the current keyframe measures.
bool DepthHolds(const DetectedLoop& loop, double bf, const LoopVerificationOptions& o,
                LoopVerification* v) {
  if (!o.check_depth || bf <= 0.0) return true;
  const map::KeyFrame& cur = *loop.current;
  const geometry::SE3 T_cw = MetricPose(loop.S_cur_world);
  int consistent = 0;
  for (size_t i = 0; i < loop.matched.size(); ++i) {
    const auto& p = loop.matched[i];
    if (!p || i >= cur.frame.depth.size()) continue;
    const double z = cur.frame.depth[i];
    if (!(z > 0.0)) continue;
    const double z_pred = (T_cw * p->position).z();
    // Stereo depth sigma at this octave: z^2 / bf x the keypoint's pixel sigma.
    const int octave = cur.frame.keypoints_undistorted[i].octave;
    const double sigma = z * z / bf * std::sqrt(cur.frame.level_sigma2[octave]);
    ++v->depth_samples;
    if (std::abs(z_pred - z) <= o.depth_tolerance_ratio * z + 3.0 * sigma) ++consistent;
  }
  if (v->depth_samples < o.min_depth_samples) return true;
  v->depth_consistent = static_cast<double>(consistent) / v->depth_samples;
  if (v->depth_consistent < o.min_depth_consistent) {
    v->rejected_by = "depth";
    return false;
  }
  return true;
}

// Rule 3: the loop side seen from the current keyframe's neighbours as well.
bool NeighboursHold(const DetectedLoop& loop, const camera::PinholeCamera& camera,
                    const LoopVerificationOptions& o, LoopVerification* v) {
  if (!o.check_neighbours || o.neighbours == 0) return true;
  const map::KeyFrame& cur = *loop.current;
  std::set<uint64_t> loop_group = {loop.loop->id};
  for (const auto& n : loop.loop->BestCovisibles(-1)) loop_group.insert(n->id);
  const geometry::Sim3 S_cur_world_odom(cur.T_cam_world());
  for (const KeyFramePtr& n : cur.BestCovisibles(-1)) {
    if (v->neighbours_tried >= o.neighbours) break;
    if (n->bad() || loop_group.count(n->id)) continue;
    ++v->neighbours_tried;
    // The neighbour's pose as the loop corrects it: its odometry pose relative to the current
    // keyframe, composed with the current keyframe's corrected pose.
    const geometry::Sim3 S_n_cur = geometry::Sim3(n->T_cam_world()) * S_cur_world_odom.Inverse();
    PointMatches matched(n->points.size());
    const int found = SearchByProjectionSim3(*n, S_n_cur * loop.S_cur_world, loop.loop_points,
                                             camera, kNeighbourRadius, &matched);
    if (found >= o.min_neighbour_matches) ++v->neighbours_passing;
  }
  // With a single neighbour outside the loop's group (a camera turning on the spot sees little
  // of the loop side from the keyframe before) one view is no evidence either way.
  if (v->neighbours_tried < 2) return true;
  const int needed = std::min(o.min_neighbours_passing, v->neighbours_tried);
  if (v->neighbours_passing < needed) {
    v->rejected_by = "neighbours";
    return false;
  }
  return true;
}

// Rule 4: matches spread over the image.
bool SpreadHolds(const DetectedLoop& loop, const camera::PinholeCamera& camera,
                 const LoopVerificationOptions& o, LoopVerification* v) {
  if (!o.check_spread) return true;
  const map::KeyFrame& cur = *loop.current;
  std::vector<int> count(static_cast<size_t>(o.spread_cols * o.spread_rows), 0);
  for (size_t i = 0; i < loop.matched.size(); ++i) {
    if (!loop.matched[i]) continue;
    const cv::Point2f& pt = cur.frame.keypoints_undistorted[i].pt;
    const int cx =
        std::clamp(static_cast<int>(pt.x * o.spread_cols / camera.width()), 0, o.spread_cols - 1);
    const int cy =
        std::clamp(static_cast<int>(pt.y * o.spread_rows / camera.height()), 0, o.spread_rows - 1);
    ++count[static_cast<size_t>(cy * o.spread_cols + cx)];
  }
  v->spread_cells =
      static_cast<int>(std::count_if(count.begin(), count.end(), [](int c) { return c >= 2; }));
  if (v->spread_cells < o.min_spread_cells) {
    v->rejected_by = "spread";
    return false;
  }
  return true;
}

}  // namespace

void PathLength(const map::Map& map, uint64_t from_id, uint64_t to_id, double* metres,
                double* degrees) {
  if (from_id > to_id) std::swap(from_id, to_id);
  *metres = 0.0;
  *degrees = 0.0;
  const map::KeyFrame* previous = nullptr;
  const auto& keyframes = map.keyframes();
  for (auto it = keyframes.lower_bound(from_id); it != keyframes.end() && it->first <= to_id;
       ++it) {
    const map::KeyFrame& kf = *it->second;
    if (kf.bad()) continue;
    if (previous) {
      *metres += (kf.CameraCenter() - previous->CameraCenter()).norm();
      *degrees += geometry::RotationAngle(kf.T_cam_world().rotation() *
                                          previous->T_cam_world().rotation().inverse()) *
                  kRadToDeg;
    }
    previous = &kf;
  }
}

LoopVerification VerifyLoop(const map::Map& map, const DetectedLoop& loop,
                            const camera::PinholeCamera& camera, double bf,
                            const LoopVerificationOptions& options) {
  LoopVerification v;
  Measure(map, loop, &v);
  v.accepted = DriftHolds(options, &v) && RevisitHolds(options, &v) &&
               DepthHolds(loop, bf, options, &v) && NeighboursHold(loop, camera, options, &v) &&
               SpreadHolds(loop, camera, options, &v);
  return v;
}

}  // namespace moslam::slam
