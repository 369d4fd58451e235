#include "moslam/slam/tracker.h"
#include "moslam/slam/camera_model.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <mutex>
#include <set>
#include <utility>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "moslam/feature/matcher.h"
#include "moslam/slam/frame_pose.h"
#include "moslam/slam/relocalizer.h"
#include "moslam/util/check.h"

namespace moslam::slam {

namespace {

using Clock = std::chrono::steady_clock;
double MsSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

// ORB-SLAM2's thresholds: projection radius (pixels at level 0) of the motion model for stereo /
// RGB-D (th = 7, doubled when too few matches), and of the local-map search (th = 1 times
// RadiusByViewingCos, 2.5 to 4).
constexpr float kMotionModelRadius = 7.0f;
constexpr float kMonoMotionModelRadius = 15.0f;  // ORB-SLAM2: th = 15 for monocular
constexpr float kLocalMapRadius = 3.0f;
constexpr int kMinMotionModelMatches = 20;
constexpr int kMinTrackingMatches = 10;
constexpr int kMinReferenceMatches = 15;
// The motion model keeping under this share of the last frame's inliers is cross-checked with
// the reference keyframe (Tracker::CrossCheckWithReference).
constexpr double kSuspectMotionShare = 0.25;
constexpr int kMaxLocalKeyFrames = 80;
// Local-map inliers needed in the first max_frames_between_keyframes frames after a
// relocalization (ORB-SLAM2's TrackLocalMap).
constexpr int kMinInliersAfterRelocalization = 50;
// Votes in the pose consensus: 1 + min(age, kSupportAge) / kSupportUnit, age in seconds since the
// tracker first matched the point: from 1 (new) to 5 (known for 10 s).
constexpr double kSupportAge = 10.0, kSupportUnit = 2.5;
// A frame more than this many regular intervals after the last tracked one follows a gap.
constexpr double kGapIntervals = 3.0;

}  // namespace

Tracker::Tracker(map::Map* map, const camera::PinholeCamera& camera, double bf,
                 const TrackerOptions& options, KeyFrameSink* sink)
    : map_(map),
      camera_(camera),
      model_(CameraModelFor(camera, bf)),
      options_(options),
      sink_(sink),
      static_scores_(options.static_scores),
      young_points_(options.young_points) {
  MOSLAM_CHECK(map_ != nullptr && sink_ != nullptr);
  options_.Check();
}

TrackOutcome Tracker::Track(feature::Frame frame, const FrameImages& images) {
  TrackOutcome out;
  const size_t n = frame.size();
  current_.frame = std::move(frame);
  current_.points.assign(n, nullptr);
  current_.outlier.assign(n, false);
  current_chi2_.assign(n, 0.0);
  prediction_.reset();
  young_points_moved_ = false;
  ++frames_since_keyframe_;
  ++frames_since_relocalization_;

  if (!initialized_ && options_.monocular) {
    TrackOutcome init = InitializeMonocular();
    if (init.status == TrackStatus::kInitialized) {
      last_ = std::move(current_);
      last_ok_ = true;
    }
    return init;
  }
  if (!initialized_) {
    const auto t0 = Clock::now();
    std::shared_ptr<map::KeyFrame> keyframe;
    {
      std::lock_guard<std::mutex> lock(map_->mutex());
      if (!Initialize()) {
        out.reason = "too few depth points to initialize";
        RecordPose(false);
        return out;
      }
      keyframe = reference_;
      out.num_inliers = keyframe->TrackedMapPoints(1);
      RecordPose(true);  // reads the keyframe's pose: under the lock, mapping may move it
    }
    sink_->InsertKeyFrame(keyframe);
    out.keyframe_ms = MsSince(t0);
    out.status = TrackStatus::kInitialized;
    out.new_keyframe = true;
    out.T_cam_world = current_.T_cam_world;
    last_ = std::move(current_);
    last_ok_ = true;
    return out;
  }

  auto t0 = Clock::now();
  bool ok = false;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    RefreshLastFrame();
    // Lost with a keyframe database: only relocalization, as ORB-SLAM2.
    const bool relocalize_only = database_ && !last_ok_;
    if (have_velocity_ && last_ok_) {
      out.num_matches = TrackWithMotionModel();
      ok = out.num_matches >= kMinTrackingMatches;
      if (ok && options_.motion_cross_check &&
          out.num_matches < kSuspectMotionShare * last_inliers_) {
        out.num_matches = CrossCheckWithReference(out.num_matches);
      }
    }
    if (!ok && !relocalize_only) {
      out.num_matches = TrackReferenceKeyFrame();
      ok = out.num_matches >= kMinTrackingMatches;
      if (!ok) out.reason = "too few matches with the motion model and the reference keyframe";
    }
    // Lost since an earlier frame, but not long ago: the last tracked frame's points where the
    // camera should be now, before the database is asked.
    if (!ok && relocalize_only) {
      if (const auto predicted = RecoveryPrediction()) {
        // Twice the motion model's radii: the prediction spans several frames.
        out.num_matches = TrackFromPrediction(*predicted, 2.0f);
        ok = out.num_matches >= kMinTrackingMatches;
        out.recovered = ok;
        if (ok) frames_since_relocalization_ = 0;  // local map: the stricter count, as after one
      }
    }
    if (!ok && database_) {
      ok = Relocalize(&out);
      if (!ok)
        out.reason += out.reason.empty() ? "relocalization failed" : "; relocalization failed";
    }
  }
  out.track_ms = MsSince(t0);
  if (ok) {
    t0 = Clock::now();
    std::lock_guard<std::mutex> lock(map_->mutex());
    out.num_inliers = TrackLocalMap(&out);
    last_inliers_ = out.num_inliers;
    const bool recently_relocalized =
        frames_since_relocalization_ < static_cast<uint64_t>(options_.max_frames_between_keyframes);
    ok = out.num_inliers >= (recently_relocalized
                                 ? std::max(options_.min_inliers, kMinInliersAfterRelocalization)
                                 : options_.min_inliers);
    if (!ok) out.reason = "too few inliers after local-map tracking";
    // The motion model's error on this frame sets the prior of the next checks (young_points.h);
    // not on a frame whose pose the check moved: that difference is the mover's earlier pull
    // being undone, not the motion model's error.
    if (ok && prediction_ && !out.recovered && !young_points_moved_ && !options_.monocular &&
        options_.young_points.enabled) {
      young_points_.RecordPrediction(current_.T_cam_world, *prediction_);
    }
    if (ok && !options_.localization) out.movable = JudgeLocalPoints(images);
    out.local_map_ms = MsSince(t0);
  }
  if (!ok) {
    out.status = TrackStatus::kLost;
    out.relocalized = false;
    out.recovered = false;
    RecordPose(false);
    last_ok_ = false;
    have_velocity_ = false;
    recent_frames_.clear();
    return out;
  }
  velocity_ = current_.T_cam_world * last_.T_cam_world.Inverse();
  // After a relocalization the last frame is a lost one: no motion model until the next frame
  // (ORB-SLAM2 tracks the reference keyframe up to mnLastRelocFrameId + 1). After a recovery
  // the velocity spans the lost frames: the next frame tracks the reference keyframe too.
  have_velocity_ = !out.relocalized && !out.recovered;
  const double dt = current_.frame.timestamp - last_.frame.timestamp;
  // Tracked across a gap in the stream (dropped frames; the pose consensus finds such frames
  // from their own matches): the motion spans the gap, and as the next frame's prediction it
  // would repeat all of it. Scale it to the last regular frame interval instead.
  if (have_velocity_ && have_recovery_motion_ && dt > kGapIntervals * recovery_dt_) {
    velocity_ = geometry::SE3::Exp((recovery_dt_ / dt) * velocity_.Log());
  } else if (have_velocity_ && dt > 0.0) {
    recovery_motion_ = velocity_;
    recovery_dt_ = dt;
    have_recovery_motion_ = true;
  }

  t0 = Clock::now();
  std::shared_ptr<map::KeyFrame> keyframe;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    if (NeedNewKeyFrame()) {
      keyframe = CreateKeyFrame();
      AppendMovingKeypoints(&out.inconsistent);
    }
    RecordPose(true);  // reads the reference keyframe's pose: under the lock
  }
  if (keyframe) sink_->InsertKeyFrame(keyframe);
  out.keyframe_ms = MsSince(t0);
  out.new_keyframe = keyframe != nullptr;
  out.status = TrackStatus::kOk;
  out.T_cam_world = current_.T_cam_world;
  // After a relocalization or a recovery the frames before may be anywhere (a kidnap): the
  // moving-keypoint check starts again from this frame.
  if (out.relocalized || out.recovered) recent_frames_.clear();
  RememberFrame();
  // ORB-SLAM2 drops the outliers before the frame becomes the last frame.
  for (size_t i = 0; i < current_.points.size(); ++i) {
    if (current_.outlier[i]) current_.points[i] = nullptr;
  }
  last_ = std::move(current_);
  last_ok_ = true;
  return out;
}

void Tracker::StartFromLoadedMap() {
  initialized_ = true;
  last_ok_ = false;
  have_velocity_ = false;
  have_recovery_motion_ = false;
  reference_ = nullptr;
  last_keyframe_ = nullptr;
  // The map may hold keyframes up to its size: no "just relocalized" pause on keyframes.
  frames_since_keyframe_ = 0;
}

bool Tracker::Initialize() {
  if (current_.frame.NumWithDepth() < options_.min_init_points) return false;
  current_.T_cam_world = geometry::SE3::Identity();
  auto kf = map_->CreateKeyFrame(current_.frame, current_.T_cam_world);
  const geometry::SE3 T_world_cam = kf->T_world_cam();
  for (size_t i = 0; i < current_.frame.size(); ++i) {
    const auto p_cam = current_.frame.UnprojectCamera(i, camera_);
    if (!p_cam) continue;
    auto point = map_->CreateMapPoint(T_world_cam * *p_cam, kf);
    point->AddObservation(kf, i);
    kf->points[i] = point;
    point->ComputeDistinctiveDescriptor();
    point->UpdateNormalAndDepth();
    current_.points[i] = point;
  }
  reference_ = kf;
  last_keyframe_ = kf;
  frames_since_keyframe_ = 0;
  local_keyframes_ = {kf};
  UpdateLocalPoints();
  initialized_ = true;
  return true;
}

void Tracker::RefreshLastFrame() {
  // Points fused or culled by local mapping since the last frame (ORB-SLAM2's
  // CheckReplacedInLastFrame), and the last pose re-read from its reference keyframe, which
  // local bundle adjustment may have moved (ORB-SLAM2's UpdateLastFrame).
  for (auto& p : last_.points) {
    if (!p || !p->bad) continue;
    auto replacement = p->replaced_by.lock();
    p = (replacement && !replacement->bad) ? replacement : nullptr;
  }
  // A reference keyframe culled by local mapping hands over to its spanning-tree parent.
  while (reference_ && reference_->bad() && reference_->parent()) {
    reference_ = reference_->parent();
  }
  if (!frame_poses_.empty()) {
    const FramePose& fp = frame_poses_.back();
    if (fp.reference && !fp.reference->bad()) {
      last_.T_cam_world = fp.T_cam_ref * fp.reference->T_cam_world();
    }
  }
}

int Tracker::SearchByProjection(const std::vector<std::shared_ptr<map::MapPoint>>& candidates,
                                float radius, bool check_right) {
  const feature::Frame& f = current_.frame;
  const float log_scale = f.num_levels() > 1 ? std::log(f.scale_factors[1]) : 1.0f;
  const geometry::SE3& T = current_.T_cam_world;
  const Eigen::Vector3d center = T.Inverse().translation();
  std::vector<feature::ProjectedPoint> projected;
  std::vector<size_t> which;
  for (size_t k = 0; k < candidates.size(); ++k) {
    const auto& p = candidates[k];
    if (!p || p->bad || p->descriptor.empty()) continue;
    const Eigen::Vector3d pc = T * p->position;
    if (pc.z() <= 0.0) continue;
    const double inv_z = 1.0 / pc.z();
    const float u = static_cast<float>(model_.fx * pc.x() * inv_z + model_.cx);
    const float v = static_cast<float>(model_.fy * pc.y() * inv_z + model_.cy);
    if (u < f.bounds.min_x || u > f.bounds.max_x || v < f.bounds.min_y || v > f.bounds.max_y) {
      continue;
    }
    const float dist = static_cast<float>((p->position - center).norm());
    feature::ProjectedPoint pp;
    pp.pixel = Eigen::Vector2f(u, v);
    pp.octave = p->PredictScale(dist, log_scale, f.num_levels());
    pp.descriptor = p->descriptor.ptr<uint8_t>();
    pp.u_right = check_right && model_.bf > 0.0 ? static_cast<float>(u - model_.bf * inv_z) : -1.0f;
    projected.push_back(pp);
    which.push_back(k);
  }
  feature::ProjectionMatchOptions options;
  options.radius = radius;
  const std::vector<int> matches = feature::MatchByProjection(f, projected, options);
  int n = 0;
  for (size_t j = 0; j < matches.size(); ++j) {
    const int idx = matches[j];
    if (idx < 0 || current_.points[idx]) continue;
    current_.points[idx] = candidates[which[j]];
    current_.outlier[idx] = false;
    ++n;
  }
  return n;
}

int Tracker::TrackWithMotionModel() { return TrackFromPrediction(velocity_ * last_.T_cam_world); }

int Tracker::TrackFromPrediction(const geometry::SE3& predicted, float radius_scale) {
  current_.T_cam_world = predicted;
  prediction_ = predicted;
  std::vector<std::shared_ptr<map::MapPoint>> candidates;
  for (const auto& p : last_.points) {
    if (p && !p->bad) candidates.push_back(p);
  }
  const float radius =
      radius_scale * (options_.monocular ? kMonoMotionModelRadius : kMotionModelRadius);
  int n = SearchByProjection(candidates, radius, true);
  if (n < kMinMotionModelMatches) {
    std::fill(current_.points.begin(), current_.points.end(), nullptr);
    n = SearchByProjection(candidates, 2.0f * radius, true);
  }
  if (n < kMinMotionModelMatches) return n;
  OptimizeCurrentPose();
  return DiscardOutliers();
}

int Tracker::CrossCheckWithReference(int motion_inliers) {
  // A prediction far off (a turn that stops at once, a jolt) finds few of the last frame's
  // points in its radius, and among repeated structure (a facade of identical windows) the pose
  // then settles on an alias a window or two over, which the local map confirms and the next
  // predictions repeat (street_repeat_loop seed 3, frame 233: the yaw rate drops from 16 deg/s
  // to 0 at the end of a corner, the motion model keeps 33 of the last frame's 576 inliers and
  // puts the camera 1.7 m back). The reference keyframe's descriptor matches (ratio test, no
  // prediction) are tried as well, and the pose with more inliers is kept.
  const geometry::SE3 motion_pose = current_.T_cam_world;
  std::vector<std::shared_ptr<map::MapPoint>> motion_points = current_.points;
  std::vector<bool> motion_outlier = current_.outlier;
  std::vector<double> motion_chi2 = current_chi2_;
  const int reference_inliers = TrackReferenceKeyFrame();
  if (reference_inliers > motion_inliers) {
    spdlog::info(
        "frame at {:.3f} s: the motion model kept {} of the last frame's {} inliers, the reference "
        "keyframe {}: its pose is taken ({:.2f} m from the motion model's)",
        current_.frame.timestamp, motion_inliers, last_inliers_, reference_inliers,
        (current_.T_cam_world.Inverse().translation() - motion_pose.Inverse().translation())
            .norm());
    return reference_inliers;
  }
  current_.T_cam_world = motion_pose;
  current_.points = std::move(motion_points);
  current_.outlier = std::move(motion_outlier);
  current_chi2_ = std::move(motion_chi2);
  return motion_inliers;
}

int Tracker::TrackReferenceKeyFrame() {
  std::fill(current_.points.begin(), current_.points.end(), nullptr);
  std::fill(current_.outlier.begin(), current_.outlier.end(), false);
  const auto& ref = reference_;
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  std::vector<size_t> index;
  for (size_t i = 0; i < ref->points.size(); ++i) {
    const auto& p = ref->points[i];
    if (!p || p->bad) continue;
    keypoints.push_back(ref->frame.keypoints_undistorted[i]);
    descriptors.push_back(ref->frame.descriptors.row(static_cast<int>(i)));
    index.push_back(i);
  }
  if (keypoints.empty()) return 0;
  feature::DescriptorMatchOptions options;
  options.ratio = 0.7f;  // ORB-SLAM2's SearchByBoW in TrackReferenceKeyFrame
  const auto matches =
      feature::MatchByDescriptor(keypoints, descriptors, current_.frame.keypoints_undistorted,
                                 current_.frame.descriptors, options);
  if (static_cast<int>(matches.size()) < kMinReferenceMatches) {
    return static_cast<int>(matches.size());
  }
  for (const auto& m : matches) current_.points[m.index2] = ref->points[index[m.index1]];
  current_.T_cam_world = last_.T_cam_world;
  OptimizeCurrentPose();
  return DiscardOutliers();
}

bool Tracker::Relocalize(TrackOutcome* out) {
  // The BoW needs no lock, but this runs inside the tracking step's lock scope; transforming
  // ~1000 descriptors takes about a millisecond.
  const KeyFrameBow bow = database_->ComputeBow(current_.frame.descriptors);
  RelocalizerOptions options;
  options.num_threads = options_.num_threads;
  const std::optional<RelocalizationPrior> prior = RecoveryPrior();
  const RelocalizationResult r =
      slam::Relocalize(*database_, current_.frame, bow, model_, options, prior);
  if (r.refused_by_prior > 0) {
    const std::string refused = fmt::format(
        "relocalization refused {} pose(s) that a short loss cannot explain, the nearest {:.2f} "
        "from the predicted camera centre (allowed {:.2f})",
        r.refused_by_prior, r.nearest_refused, prior->radius);
    spdlog::info("frame at {:.3f} s: {}", current_.frame.timestamp, refused);
    if (!r.success) out->reason += (out->reason.empty() ? "" : "; ") + refused;
  }
  if (!r.success) return false;
  current_.T_cam_world = r.T_cam_world;
  current_.points = r.points;
  std::fill(current_.outlier.begin(), current_.outlier.end(), false);
  reference_ = r.keyframe;
  frames_since_relocalization_ = 0;
  out->num_matches = r.num_inliers;
  out->relocalized = true;
  return true;
}

int Tracker::OptimizeCurrentPose() {
  std::vector<size_t> index;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> weights;
  bool weighted = false;
  for (size_t i = 0; i < current_.points.size(); ++i) {
    if (!current_.points[i]) continue;
    index.push_back(i);
    points.push_back(current_.points[i]->position);
    weights.push_back(static_scores_.Weight(current_.points[i]->id));
    weighted = weighted || weights.back() < 1.0;
  }
  if (!weighted) weights.clear();  // all 1: the unweighted problem, bit for bit
  geometry::SE3 start = current_.T_cam_world;
  std::vector<bool> initial_outlier;
  const std::vector<optim::Observation> observations =
      FrameObservations(current_.frame, index, FarWeighting());
  if (options_.pose_consensus && !options_.monocular) {
    std::vector<Eigen::Vector3d> points_cam;
    std::vector<double> support;
    points_cam.reserve(index.size());
    const double t = current_.frame.timestamp;
    for (size_t i : index) {
      const auto p = current_.frame.UnprojectCamera(i, camera_);
      points_cam.push_back(p ? *p : Eigen::Vector3d::Constant(std::nan("")));
      // A point known for longer votes more, up to kSupportAge seconds (pose_consensus.h).
      const double age = static_scores_.Age(current_.points[i]->id, t);
      support.push_back(1.0 + std::min(age, kSupportAge) / kSupportUnit);
    }
    const optim::PoseConsensus consensus = optim::FindPoseConsensus(
        model_, start, points, observations, points_cam, options_.consensus, support);
    start = consensus.T_cam_world;
    initial_outlier.resize(index.size());
    for (size_t k = 0; k < index.size(); ++k) initial_outlier[k] = !consensus.inlier[k];
  }
  optim::PoseOptimizerOptions pose_options;
  pose_options.num_threads = options_.num_threads;
  optim::PoseOptimizerResult result = optim::OptimizePose(model_, start, points, observations,
                                                          pose_options, initial_outlier, weights);
  if (result.num_inliers < 3) return 0;
  if (!options_.monocular) CheckYoungPoints(index, points, start, &result);
  current_.T_cam_world = result.T_cam_world;
  for (size_t k = 0; k < index.size(); ++k) {
    current_.outlier[index[k]] = !result.inlier[k];
    current_chi2_[index[k]] = result.chi2[k];
  }
  return result.num_inliers;
}

int Tracker::DiscardOutliers() {
  int n = 0;
  for (size_t i = 0; i < current_.points.size(); ++i) {
    if (!current_.points[i]) continue;
    if (current_.outlier[i]) {
      current_.points[i] = nullptr;
      current_.outlier[i] = false;
    } else if (current_.points[i]->num_observations() > 0) {
      ++n;
    }
  }
  return n;
}

int Tracker::TrackLocalMap(TrackOutcome* out) {
  UpdateLocalKeyFrames();
  UpdateLocalPoints();
  SearchLocalPoints();
  OptimizeCurrentPose();
  out->residual_erased = JudgeResiduals(&out->inconsistent);
  int inliers = 0;
  for (size_t i = 0; i < current_.points.size(); ++i) {
    auto& p = current_.points[i];
    if (!p) continue;
    if (!current_.outlier[i]) {
      if (!options_.localization) ++p->found;  // culling statistics: the map stays as loaded
      if (p->num_observations() > 0) ++inliers;
    } else if (!options_.monocular) {
      // Stereo / RGB-D: outliers are dropped at once (ORB-SLAM2's TrackLocalMap); monocular keeps
      // them flagged until the frame becomes the last frame.
      p = nullptr;
      current_.outlier[i] = false;
    }
  }
  return inliers;
}

void Tracker::UpdateLocalKeyFrames() {
  // Keyframes that see the frame's points, with the number seen (ORB-SLAM2).
  std::map<uint64_t, int> counter;
  std::map<uint64_t, std::shared_ptr<map::KeyFrame>> by_id;
  for (auto& p : current_.points) {
    if (!p) continue;
    if (p->bad) {
      p = nullptr;
      continue;
    }
    for (const auto& [kf_id, obs] : p->observations()) {
      auto kf = obs.keyframe.lock();
      if (!kf || kf->bad()) continue;
      ++counter[kf_id];
      by_id[kf_id] = kf;
    }
  }
  if (counter.empty()) return;
  local_keyframes_.clear();
  std::set<uint64_t> added;
  int best = 0;
  for (const auto& [kf_id, count] : counter) {
    local_keyframes_.push_back(by_id[kf_id]);
    added.insert(kf_id);
    if (count > best) {
      best = count;
      reference_ = by_id[kf_id];
    }
  }
  // Neighbours: one best covisible, one child and the parent of each (ORB-SLAM2).
  const size_t first_ring = local_keyframes_.size();
  for (size_t k = 0; k < first_ring; ++k) {
    if (static_cast<int>(local_keyframes_.size()) >= kMaxLocalKeyFrames) break;
    const auto kf = local_keyframes_[k];
    for (const auto& n : kf->BestCovisibles(10)) {
      if (added.insert(n->id).second) {
        local_keyframes_.push_back(n);
        break;
      }
    }
    for (uint64_t child_id : kf->children()) {
      auto child = map_->keyframe(child_id);
      if (child && !child->bad() && added.insert(child_id).second) {
        local_keyframes_.push_back(child);
        break;
      }
    }
    auto parent = kf->parent();
    if (parent && !parent->bad() && added.insert(parent->id).second) {
      local_keyframes_.push_back(parent);
    }
  }
}

void Tracker::UpdateLocalPoints() {
  local_points_.clear();
  std::set<uint64_t> added;
  for (const auto& kf : local_keyframes_) {
    for (const auto& p : kf->points) {
      if (p && !p->bad && added.insert(p->id).second) local_points_.push_back(p);
    }
  }
}

void Tracker::SearchLocalPoints() {
  std::set<uint64_t> in_frame;
  for (auto& p : current_.points) {
    if (!p) continue;
    if (p->bad) {
      p = nullptr;
      continue;
    }
    if (!options_.localization) ++p->visible;
    in_frame.insert(p->id);
  }
  // Frustum test of ORB-SLAM2's isInFrustum: in front, inside the scale-invariance range and
  // seen at less than 60 degrees from the mean viewing direction.
  const Eigen::Vector3d center = current_.T_cam_world.Inverse().translation();
  std::vector<std::shared_ptr<map::MapPoint>> candidates;
  for (const auto& p : local_points_) {
    if (p->bad || in_frame.count(p->id)) continue;
    const Eigen::Vector3d pc = current_.T_cam_world * p->position;
    if (pc.z() <= 0.0) continue;
    const double u = model_.fx * pc.x() / pc.z() + model_.cx;
    const double v = model_.fy * pc.y() / pc.z() + model_.cy;
    const auto& b = current_.frame.bounds;
    if (u < b.min_x || u > b.max_x || v < b.min_y || v > b.max_y) continue;
    const Eigen::Vector3d ray = p->position - center;
    const double dist = ray.norm();
    if (dist < 0.8 * p->min_distance || dist > 1.2 * p->max_distance) continue;
    if (ray.dot(p->normal) < 0.5 * dist) continue;
    if (!options_.localization) ++p->visible;
    candidates.push_back(p);
  }
  // ORB-SLAM2 checks the right coordinate only in the motion-model search.
  SearchByProjection(candidates, kLocalMapRadius, false);
}

bool Tracker::NeedNewKeyFrame() const {
  // ORB-SLAM2's Tracking::NeedNewKeyFrame. Monocular: no close points, a higher reference ratio
  // (0.9: keyframes more often, they are the only source of new points), no "tracking weak"
  // trigger, and no insertion while local mapping is busy.
  if (options_.localization) return false;
  const size_t num_keyframes = map_->keyframes().size();
  // No keyframe just after a relocalization (unless the map is still small).
  const auto max_frames = static_cast<uint64_t>(options_.max_frames_between_keyframes);
  if (frames_since_relocalization_ < max_frames && num_keyframes > max_frames) return false;
  const int min_obs = num_keyframes <= 2 ? 2 : 3;
  const int ref_matches = reference_->TrackedMapPoints(min_obs);
  const bool idle = sink_->MappingIdle();
  int tracked_close = 0, untracked_close = 0;
  const feature::Frame& f = current_.frame;
  for (size_t i = 0; i < f.size(); ++i) {
    if (f.depth[i] <= 0.0f || f.depth[i] >= options_.close_depth) continue;
    if (current_.points[i] && !current_.outlier[i]) {
      ++tracked_close;
    } else if (!f.NearMovable(i)) {  // those never become points (CreateKeyFrame)
      ++untracked_close;
    }
  }
  const bool need_close = tracked_close < 100 && untracked_close > 70;
  const double th_ref = num_keyframes < 2 ? 0.4 : (options_.monocular ? 0.9 : 0.75);
  const bool c1a =
      frames_since_keyframe_ >= static_cast<uint64_t>(options_.max_frames_between_keyframes);
  const bool weak = last_inliers_ < ref_matches * 0.25 || need_close;
  const bool c1c = !options_.monocular && weak;
  const bool c2 = (last_inliers_ < ref_matches * th_ref || need_close) && last_inliers_ > 15;
  if (!((c1a || idle || c1c) && c2)) return false;
  if (idle) return true;
  if (options_.monocular) {
    // Mapping becomes idle sooner, and the next frame gets its keyframe in (ORB-SLAM2; only for
    // monocular here, which has no other source of new points).
    sink_->InterruptMapping();
    return false;
  }
  // Stereo/RGB-D: ORB-SLAM2 queues at most 3 keyframes. When mapping lags further behind (a
  // loaded machine; frames as fast as tracking takes them) that leaves a weak tracker on a
  // thinning map: its inliers fall to a few dozen and its poses drift by decimetres while the
  // keyframes stay accurate. A weak tracker's keyframe goes in regardless; the queue's capacity
  // bounds it (InsertKeyFrame then blocks tracking until mapping takes one: backpressure, and
  // mapping gets the CPU it needs). The running local BA is stopped so that happens sooner
  // (ORB-SLAM2's InterruptBA).
  if (weak) {
    sink_->InterruptMapping();
    return true;
  }
  return sink_->QueuedKeyFrames() < 3;
}

std::shared_ptr<map::KeyFrame> Tracker::CreateKeyFrame() {
  FlagMovingKeypoints();  // they seed no point, here or in local mapping
  auto kf = map_->CreateKeyFrame(current_.frame, current_.T_cam_world);
  for (size_t i = 0; i < current_.points.size(); ++i) {
    if (current_.points[i] && !current_.outlier[i]) kf->points[i] = current_.points[i];
  }
  // New points from the closest depth measurements: all closer than close_depth, and at least
  // the 100 closest (ORB-SLAM2's CreateNewKeyFrame).
  std::vector<std::pair<float, size_t>> by_depth;
  const feature::Frame& f = current_.frame;
  for (size_t i = 0; i < f.size(); ++i) {
    // No new point at a movable mask's border or where the keypoint was seen moving.
    if (f.depth[i] > 0.0f && !f.SeedsNoPoint(i)) by_depth.emplace_back(f.depth[i], i);
  }
  std::sort(by_depth.begin(), by_depth.end());
  const geometry::SE3 T_world_cam = kf->T_world_cam();
  int n = 0;
  for (const auto& [depth, i] : by_depth) {
    const auto& existing = current_.points[i];
    if (!existing || existing->num_observations() < 1) {
      const auto p_cam = f.UnprojectCamera(i, camera_);
      if (p_cam) {
        auto point = map_->CreateMapPoint(T_world_cam * *p_cam, kf);
        point->AddObservation(kf, i);
        kf->points[i] = point;
        point->ComputeDistinctiveDescriptor();
        point->UpdateNormalAndDepth();
        current_.points[i] = point;
        current_.outlier[i] = false;
      }
    }
    ++n;
    if (depth > options_.close_depth && n > 100) break;
  }
  reference_ = kf;
  last_keyframe_ = kf;
  frames_since_keyframe_ = 0;
  return kf;
}

void Tracker::RecordPose(bool ok) {
  FramePose fp;
  fp.timestamp = current_.frame.timestamp;
  if (ok) {
    fp.reference = reference_;
    fp.T_cam_ref = current_.T_cam_world * reference_->T_world_cam();
  }
  frame_poses_.push_back(fp);
}

}  // namespace moslam::slam
