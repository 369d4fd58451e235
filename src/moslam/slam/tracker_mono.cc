// Monocular map initialization of the Tracker (ORB-SLAM2's Tracking::MonocularInitialization and
// CreateInitialMapMonocular, Mur-Artal et al. 2015 Sec. IV): the first frame with enough features
// becomes the reference; each later frame is matched to it (SearchForInitialization) and handed to
// the two-view initializer; on success two keyframes and the triangulated points form the map,
// refined by a full bundle adjustment and scaled to a median scene depth of 1.
// Kept apart from tracker.cc, which holds what all sensors share.
#include <algorithm>
#include <chrono>
#include <mutex>
#include <utility>

#include <spdlog/spdlog.h>

#include "moslam/optim/bundle_adjuster.h"
#include "moslam/slam/tracker.h"

namespace moslam::slam {

namespace {

double MsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

Eigen::Vector2d Pixel(const feature::Frame& f, size_t i) {
  return {f.keypoints_undistorted[i].pt.x, f.keypoints_undistorted[i].pt.y};
}

optim::Observation MonoObservation(const feature::Frame& f, size_t i) {
  optim::Observation o;
  o.pixel = Pixel(f, i);
  o.u_right = -1.0;
  o.inv_sigma2 = f.inv_level_sigma2[f.keypoints_undistorted[i].octave];
  return o;
}

constexpr int kInitialBaIterations = 20;  // ORB-SLAM2's GlobalBundleAdjustemnt(map, 20)
constexpr int kMinInitialPoints = 100;    // ORB-SLAM2: the second keyframe must track 100 points

}  // namespace

TrackOutcome Tracker::InitializeMonocular() {
  const auto t0 = std::chrono::steady_clock::now();
  TrackOutcome out;
  const feature::Frame& frame = current_.frame;
  const auto not_yet = [&](std::string reason) {
    out.reason = std::move(reason);
    RecordPose(false);
    return out;
  };
  if (!init_reference_) {
    if (static_cast<int>(frame.size()) <= options_.min_init_features) {
      return not_yet("monocular initialization: too few features for a reference frame");
    }
    init_reference_ = std::make_unique<feature::Frame>(frame);
    init_prev_matched_.clear();
    for (const auto& kp : frame.keypoints_undistorted) {
      init_prev_matched_.emplace_back(kp.pt.x, kp.pt.y);
    }
    return not_yet("monocular initialization: reference frame set");
  }
  if (static_cast<int>(frame.size()) <= options_.min_init_features) {
    init_reference_.reset();
    return not_yet("monocular initialization: too few features, reference dropped");
  }
  const std::vector<int> matches12 =
      SearchForInitialization(*init_reference_, frame, &init_prev_matched_);
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t i = 0; i < matches12.size(); ++i) {
    if (matches12[i] >= 0) pairs.emplace_back(i, static_cast<size_t>(matches12[i]));
  }
  out.num_matches = static_cast<int>(pairs.size());
  if (out.num_matches < options_.min_init_matches) {
    // ORB-SLAM2 drops the reference; the next frame with enough features becomes the new one.
    init_reference_.reset();
    return not_yet("monocular initialization: too few matches with the reference frame");
  }
  std::vector<Eigen::Vector2d> p1, p2;
  for (const auto& [i1, i2] : pairs) {
    p1.push_back(Pixel(*init_reference_, i1));
    p2.push_back(Pixel(frame, i2));
  }
  const MonoInitialization init = InitializeTwoView(p1, p2, camera_.K(), options_.initializer);
  if (!init.ok) return not_yet("monocular initialization: " + init.reason);

  std::vector<std::shared_ptr<map::KeyFrame>> keyframes;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    std::string reason;
    if (!CreateInitialMonocularMap(pairs, init, &reason)) {
      // ORB-SLAM2 resets the system here: initialization starts over from the next frame.
      ++rejected_initializations_;
      init_reference_.reset();
      return not_yet("monocular initialization rejected: " + reason);
    }
    keyframes = {local_keyframes_[1], local_keyframes_[0]};  // first and second view
    out.num_inliers = reference_->TrackedMapPoints(1);
    RecordPose(true);
  }
  spdlog::info("monocular map initialized ({}, R_H {:.2f}, parallax {:.1f} deg): {} points",
               ToString(init.model), init.ratio_h, init.parallax_deg, out.num_inliers);
  for (const auto& kf : keyframes) sink_->InsertKeyFrame(kf);
  init_reference_.reset();
  out.keyframe_ms = MsSince(t0);
  out.status = TrackStatus::kInitialized;
  out.new_keyframe = true;
  out.T_cam_world = current_.T_cam_world;
  return out;
}

bool Tracker::CreateInitialMonocularMap(const std::vector<std::pair<size_t, size_t>>& pairs,
                                        const MonoInitialization& init, std::string* reason) {
  const feature::Frame& f1 = *init_reference_;
  const feature::Frame& f2 = current_.frame;
  // Full bundle adjustment of the two views on plain data first, so a rejected map never enters
  // the Map (ORB-SLAM2 builds the map, adjusts it and resets everything on rejection).
  optim::BundleProblem problem;
  problem.camera = model_;
  problem.T_cam_world = {geometry::SE3::Identity(), init.T_cam2_cam1};
  problem.pose_fixed = {true, false};
  std::vector<size_t> used;  // into pairs
  for (size_t k = 0; k < pairs.size(); ++k) {
    if (!init.triangulated[k]) continue;
    const int j = static_cast<int>(problem.points_world.size());
    problem.points_world.push_back(init.points_cam1[k]);
    problem.edges.push_back({0, j, MonoObservation(f1, pairs[k].first)});
    problem.edges.push_back({1, j, MonoObservation(f2, pairs[k].second)});
    used.push_back(k);
  }
  optim::BundleAdjusterOptions ba;
  ba.iterations_first = kInitialBaIterations;  // robust, as ORB-SLAM2's global BA
  ba.iterations_second = 0;                    // which removes no outliers
  ba.num_threads = options_.num_threads;
  const optim::BundleResult result = optim::AdjustBundle(problem, ba);

  std::vector<double> depths;
  for (const auto& p : result.points_world) depths.push_back(p.z());  // camera 1 = world
  if (depths.empty()) {
    *reason = "no points";
    return false;
  }
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  const double median_depth = depths[depths.size() / 2];
  if (median_depth <= 0.0 || static_cast<int>(used.size()) < kMinInitialPoints) {
    *reason = median_depth <= 0.0 ? "negative median depth after bundle adjustment"
                                  : "fewer than 100 points after bundle adjustment";
    return false;
  }
  // Monocular scale is arbitrary: ORB-SLAM2 fixes it by a median depth of 1 in the first view.
  const double scale = 1.0 / median_depth;
  const geometry::SE3 T_cam2_world(result.T_cam_world[1].rotation(),
                                   result.T_cam_world[1].translation() * scale);
  auto kf1 = map_->CreateKeyFrame(f1, geometry::SE3::Identity());
  auto kf2 = map_->CreateKeyFrame(f2, T_cam2_world);
  for (size_t j = 0; j < used.size(); ++j) {
    const auto [i1, i2] = pairs[used[j]];
    auto point = map_->CreateMapPoint(result.points_world[j] * scale, kf2);
    point->AddObservation(kf1, i1);
    point->AddObservation(kf2, i2);
    kf1->points[i1] = point;
    kf2->points[i2] = point;
    point->ComputeDistinctiveDescriptor();
    point->UpdateNormalAndDepth();
    current_.points[i2] = point;
    current_.outlier[i2] = false;
  }
  kf1->UpdateConnections();
  kf2->UpdateConnections();
  current_.T_cam_world = T_cam2_world;
  reference_ = kf2;
  last_keyframe_ = kf2;
  frames_since_keyframe_ = 0;
  local_keyframes_ = {kf2, kf1};
  UpdateLocalPoints();
  initialized_ = true;
  return true;
}

}  // namespace moslam::slam
