#include "moslam/slam/loop_closer.h"
#include "moslam/slam/camera_model.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include <spdlog/spdlog.h>

#include "moslam/optim/sim3_optimizer.h"
#include "moslam/slam/bow_matcher.h"
#include "moslam/slam/sim3_solver.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::slam {

void LoopCloserOptions::Check() const {
  if (min_keyframes_between_loops < 0) {
    throw InputError("LoopCloserOptions.min_keyframes_between_loops must be >= 0");
  }
  if (consistency < 1) throw InputError("LoopCloserOptions.consistency must be >= 1");
  if (min_point_matches < 3) throw InputError("LoopCloserOptions.min_point_matches must be >= 3");
  if (min_sim3_inliers < 3) throw InputError("LoopCloserOptions.min_sim3_inliers must be >= 3");
  if (min_loop_matches < 1) throw InputError("LoopCloserOptions.min_loop_matches must be >= 1");
  if (recent_word_keyframes < 0 || min_recent_word_keyframes < 0) {
    throw InputError(
        "LoopCloserOptions.recent_word_keyframes and min_recent_word_keyframes must "
        "be >= 0");
  }
  if (num_threads < 1) throw InputError("LoopCloserOptions.num_threads must be >= 1");
  verification.Check();
}

namespace {

using KeyFramePtr = std::shared_ptr<map::KeyFrame>;

// ORB-SLAM2's radii (pixels at level 0): guided Sim(3) matching and the loop-side projection.
constexpr float kSim3SearchRadius = 7.5f;
constexpr float kProjectionRadius = 10.0f;

// Correspondences for the Sim(3) solver from point matches of kf1 (current) and kf2 (candidate).
std::vector<Sim3Correspondence> Correspondences(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                                const PointMatches& matches,
                                                std::vector<size_t>* index1) {
  std::vector<Sim3Correspondence> out;
  index1->clear();
  for (size_t i = 0; i < matches.size(); ++i) {
    const auto& p2 = matches[i];
    const auto& p1 = kf1.points[i];
    if (!p1 || p1->bad || !p2 || p2->bad) continue;
    const int i2 = p2->IndexIn(kf2.id);
    if (i2 < 0) continue;
    const cv::KeyPoint& k1 = kf1.frame.keypoints_undistorted[i];
    const cv::KeyPoint& k2 = kf2.frame.keypoints_undistorted[static_cast<size_t>(i2)];
    Sim3Correspondence c;
    c.p1 = kf1.T_cam_world() * p1->position;
    c.p2 = kf2.T_cam_world() * p2->position;
    c.pixel1 = Eigen::Vector2d(k1.pt.x, k1.pt.y);
    c.pixel2 = Eigen::Vector2d(k2.pt.x, k2.pt.y);
    c.sigma2_1 = kf1.frame.level_sigma2[k1.octave];
    c.sigma2_2 = kf2.frame.level_sigma2[k2.octave];
    out.push_back(c);
    index1->push_back(i);
  }
  return out;
}

}  // namespace

LoopCloser::LoopCloser(map::Map* map, const camera::PinholeCamera& camera, double bf,
                       KeyFrameDatabase* database, const LoopCloserOptions& options)
    : map_(map),
      camera_(camera),
      bf_(bf),
      model_(CameraModelFor(camera, bf)),
      database_(database),
      options_((options.Check(), options)) {
  MOSLAM_CHECK(database_ != nullptr) << "loop closing needs a keyframe database";
}

LoopCloser::~LoopCloser() { WaitForGlobalBundleAdjustment(); }

void LoopCloser::WaitForGlobalBundleAdjustment() {
  if (gba_thread_.joinable()) gba_thread_.join();
}

LoopCloserStats LoopCloser::Stats() const {
  std::lock_guard<std::mutex> lock(stats_mutex_);
  return stats_;
}

bool LoopCloser::ProcessKeyFrame(const KeyFramePtr& keyframe) {
  DetectedLoop loop;
  LoopCorrectionStats correction;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    {
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.keyframes;
    }
    if (keyframe->bad()) return false;
    std::vector<KeyFramePtr> consistent;
    if (!DetectLoop(keyframe, &consistent)) return false;
    {
      std::lock_guard<std::mutex> stats_lock(stats_mutex_);
      ++stats_.candidates_consistent;
    }
    if (!ComputeSim3(keyframe, consistent, &loop)) return false;
    correction = CorrectLoop(map_, loop, map_->loop_edges(), camera_, options_.fix_scale);
    map_->AddLoopEdge(keyframe->id, loop.loop->id);
    last_loop_keyframe_ = keyframe->id;
  }
  spdlog::info(
      "loop closed: keyframe {} with keyframe {} (scale {:.4f}, {} keyframes moved by Sim3, {} "
      "points fused; "
      "essential graph {} vertices, {} edges, cost {:.4g} -> {:.4g})",
      keyframe->id, loop.loop->id, loop.S_cur_world.scale(), correction.corrected_keyframes,
      correction.fused_points, correction.graph_vertices, correction.graph_edges,
      correction.graph_initial_cost, correction.graph_final_cost);
  {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.loops_closed;
    stats_.loops.emplace_back(keyframe->id, loop.loop->id);
    stats_.loop_times.emplace_back(keyframe->frame.timestamp, loop.loop->frame.timestamp);
  }
  if (options_.global_bundle_adjustment) StartGlobalBundleAdjustment();
  return true;
}

bool LoopCloser::DetectLoop(const KeyFramePtr& kf, std::vector<KeyFramePtr>* consistent) {
  // Too soon after the start or after the last loop (ORB-SLAM2: 10 keyframes).
  if (kf->id < last_loop_keyframe_ + static_cast<uint64_t>(options_.min_keyframes_between_loops)) {
    return false;
  }
  if (kf->bow.empty()) database_->ComputeBow(kf.get());
  std::set<uint64_t> excluded = {kf->id};
  for (const auto& n : kf->BestCovisibles(-1)) excluded.insert(n->id);
  std::vector<KeyFramePtr> found;
  const RecentWordWeights weights =
      options_.recent_word_keyframes > 0
          ? database_->RecentPastWeights(*kf, options_.recent_word_keyframes,
                                         options_.min_recent_word_keyframes)
          : RecentWordWeights();
  const double min_score = database_->MinCovisibleScore(*kf, weights);
  for (const auto& c : database_->DetectLoopCandidates(*kf, min_score, weights)) {
    if (c && !c->bad() && !excluded.count(c->id)) found.push_back(c);
  }
  if (found.empty()) {
    groups_.clear();
    return false;
  }
  // Consistency (ORB-SLAM2's DetectLoop): a candidate's group (it and its covisible keyframes)
  // continues a previous group when they share a keyframe; enough consecutive continuations make
  // the candidate a loop.
  std::vector<ConsistentGroup> next;
  std::vector<bool> continued(groups_.size(), false);
  for (const auto& c : found) {
    ConsistentGroup group;
    group.keyframes.insert(c->id);
    for (const auto& n : c->BestCovisibles(-1)) group.keyframes.insert(n->id);
    bool any = false, accepted = false;
    for (size_t g = 0; g < groups_.size(); ++g) {
      const bool shares = std::any_of(group.keyframes.begin(), group.keyframes.end(),
                                      [&](uint64_t id) { return groups_[g].keyframes.count(id); });
      if (!shares) continue;
      any = true;
      const int consistency = groups_[g].consistency + 1;
      if (!continued[g]) {
        next.push_back({group.keyframes, consistency});
        continued[g] = true;
      }
      if (consistency >= options_.consistency && !accepted) {
        consistent->push_back(c);
        accepted = true;
      }
    }
    if (!any) next.push_back({group.keyframes, 0});
  }
  groups_ = std::move(next);
  if (!consistent->empty() && spdlog::should_log(spdlog::level::debug)) {
    std::string scores;
    for (const auto& c : *consistent) {
      scores +=
          fmt::format(" kf {} ({:.3f})", c->id,
                      vocab::Vocabulary::Score(weights.Apply(kf->bow), weights.Apply(c->bow)));
    }
    spdlog::debug("loop candidates of kf {} (min covisible score {:.3f}), consistent:{}", kf->id,
                  min_score, scores);
  }
  return !consistent->empty();
}

bool LoopCloser::ComputeSim3(const KeyFramePtr& kf, const std::vector<KeyFramePtr>& candidates,
                             DetectedLoop* loop) {
  // ORB-SLAM2 takes the first candidate that passes. Among aliases (a street of identical
  // houses) several can pass, each a rigid shift of the others; the one that asks the least
  // correction of the odometry is the one drift explains best, so every candidate is tried and
  // that one is kept (without verification: the first, as ORB-SLAM2).
  bool any = false;
  double best_correction = 0.0;
  for (const auto& cand : candidates) {
    // The direct index when both keyframes have one, brute force otherwise.
    PointMatches matches = !kf->bow_features.empty() && !cand->bow_features.empty()
                               ? SearchByBoW(*kf, *cand)
                               : MatchKeyFramePoints(*kf, *cand);
    std::vector<size_t> index;
    std::vector<Sim3Correspondence> corr = Correspondences(*kf, *cand, matches, &index);
    if (static_cast<int>(corr.size()) < options_.min_point_matches) continue;
    Sim3RansacOptions ransac;
    ransac.fix_scale = options_.fix_scale;
    ransac.min_inliers = options_.min_sim3_inliers;
    ransac.seed = options_.seed * 1000003u + kf->id;
    const auto solved = SolveSim3Ransac(model_, corr, ransac);
    if (!solved) continue;
    // Keep the inlier matches, look for more with the estimate, refine on all of them.
    PointMatches inliers(kf->points.size());
    for (size_t k = 0; k < index.size(); ++k) {
      if (solved->inlier[k]) inliers[index[k]] = matches[index[k]];
    }
    SearchBySim3(*kf, *cand, solved->S_12, camera_, kSim3SearchRadius, &inliers);
    corr = Correspondences(*kf, *cand, inliers, &index);
    optim::Sim3OptimizerOptions refine;
    refine.fix_scale = options_.fix_scale;
    const optim::Sim3OptimizerResult refined =
        optim::OptimizeSim3(model_, corr, solved->S_12, refine);
    if (refined.num_inliers < options_.min_sim3_inliers) continue;
    PointMatches matched(kf->points.size());
    for (size_t k = 0; k < index.size(); ++k) {
      if (refined.inlier[k]) matched[index[k]] = inliers[index[k]];
    }
    // The loop side: the candidate and its covisible keyframes, their points projected into the
    // current keyframe with the corrected pose.
    const geometry::Sim3 S_cur_world = refined.S_12 * geometry::Sim3(cand->T_cam_world());
    std::vector<std::shared_ptr<map::MapPoint>> loop_points;
    std::set<uint64_t> seen;
    std::vector<KeyFramePtr> group = cand->BestCovisibles(-1);
    group.push_back(cand);
    for (const auto& g : group) {
      for (const auto& p : g->points) {
        if (p && !p->bad && seen.insert(p->id).second) loop_points.push_back(p);
      }
    }
    SearchByProjectionSim3(*kf, S_cur_world, loop_points, camera_, kProjectionRadius, &matched);
    const int total = static_cast<int>(
        std::count_if(matched.begin(), matched.end(), [](const auto& p) { return p != nullptr; }));
    spdlog::debug("loop candidate kf {} -> {}: {} matches, {} RANSAC inliers, {} refined, {} total",
                  kf->id, cand->id, corr.size(), solved->num_inliers, refined.num_inliers, total);
    if (total < options_.min_loop_matches) continue;
    DetectedLoop found{kf, cand, S_cur_world, std::move(matched), std::move(loop_points)};
    if (!options_.verify) {
      *loop = std::move(found);
      return true;
    }
    const LoopVerification v = Verify(found, refined.num_inliers, total);
    if (!v.accepted || (any && v.correction_m >= best_correction)) continue;
    any = true;
    best_correction = v.correction_m;
    *loop = std::move(found);
  }
  return any;
}

LoopVerification LoopCloser::Verify(const DetectedLoop& loop, int inliers, int matches) {
  const LoopVerification v = VerifyLoop(*map_, loop, camera_, bf_, options_.verification);
  const auto level = v.accepted ? spdlog::level::debug : spdlog::level::info;
  spdlog::log(
      level,
      "loop kf {} -> {} ({} Sim3 inliers, {} matches) {}: correction {:.3g} m / {:.3g} "
      "deg after a path of {:.3g} m / {:.3g} deg ({:.3g} m apart), log scale {:.3g}; depths {}/{} "
      "agree; neighbours {}/{}; {} cells",
      loop.current->id, loop.loop->id, inliers, matches,
      v.accepted ? "verified" : "refused by the " + v.rejected_by + " check", v.correction_m,
      v.correction_deg, v.path_m, v.path_deg, v.displacement_m, v.log_scale,
      static_cast<int>(std::lround(v.depth_consistent * v.depth_samples)), v.depth_samples,
      v.neighbours_passing, v.neighbours_tried, v.spread_cells);
  if (!v.accepted) {
    std::lock_guard<std::mutex> stats_lock(stats_mutex_);
    ++stats_.loops_rejected;
  }
  return v;
}

void LoopCloser::StartGlobalBundleAdjustment() {
  // One at a time: a newer loop waits for the older adjustment, whose merge is then dropped as
  // stale (the generation moved on), and starts its own.
  WaitForGlobalBundleAdjustment();
  GlobalBundleJob job;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    job = PrepareGlobalBundleAdjustment(*map_, model_, options_.far_stereo);
  }
  if (options_.synchronous) {
    RunGlobalBundleAdjustment(std::move(job));
  } else {
    gba_thread_ = std::thread(
        [this, j = std::move(job)]() mutable { RunGlobalBundleAdjustment(std::move(j)); });
  }
}

void LoopCloser::RunGlobalBundleAdjustment(GlobalBundleJob job) {
  const optim::BundleResult result = SolveGlobalBundleAdjustment(job, options_.num_threads);
  bool merged;
  {
    std::lock_guard<std::mutex> lock(map_->mutex());
    merged = MergeGlobalBundleAdjustment(map_, job, result);
  }
  spdlog::info("global bundle adjustment ({} keyframes, {} points): {}", job.keyframe_ids.size(),
               job.point_ids.size(), merged ? "merged" : "dropped, map corrected meanwhile");
  std::lock_guard<std::mutex> stats_lock(stats_mutex_);
  ++(merged ? stats_.global_ba_merged : stats_.global_ba_dropped);
}

}  // namespace moslam::slam
