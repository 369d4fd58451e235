#include "moslam/slam/loop_correction.h"

#include <algorithm>
#include <deque>

#include <spdlog/spdlog.h>

#include "moslam/slam/fuse.h"
#include "moslam/util/check.h"

namespace moslam::slam {
namespace {

// ORB-SLAM2's essential graph keeps covisibility edges of at least 100 shared points.
constexpr int kEssentialMinWeight = 100;
// ORB-SLAM2's SearchAndFuse radius (pixels at level 0).
constexpr float kLoopFuseRadius = 4.0f;

using KeyFramePtr = std::shared_ptr<map::KeyFrame>;
using SimMap = std::map<uint64_t, geometry::Sim3>;  // keyframe id -> S_cam_world

geometry::SE3 ToPose(const geometry::Sim3& S_cam_world) {
  return geometry::SE3(S_cam_world.rotation(), S_cam_world.translation() / S_cam_world.scale());
}

// The current keyframe, its covisible keyframes and every keyframe newer than it (tracked after
// it, possibly not yet connected by local mapping): they all sit on the "current" side of the loop.
std::vector<KeyFramePtr> CurrentNeighbourhood(const map::Map& map, const KeyFramePtr& current) {
  std::vector<KeyFramePtr> out = {current};
  std::set<uint64_t> ids = {current->id};
  for (const auto& kf : current->BestCovisibles(-1)) {
    if (ids.insert(kf->id).second) out.push_back(kf);
  }
  for (auto it = map.keyframes().upper_bound(current->id); it != map.keyframes().end(); ++it) {
    if (!it->second->bad() && ids.insert(it->first).second) out.push_back(it->second);
  }
  return out;
}

// Loop fusion in the current keyframe: its matched keypoints take the loop's point.
int FuseCurrentMatches(map::Map* map, const DetectedLoop& loop) {
  const KeyFramePtr& cur = loop.current;
  int fused = 0;
  for (size_t i = 0; i < loop.matched.size(); ++i) {
    const auto& loop_point = loop.matched[i];
    if (!loop_point || loop_point->bad) continue;
    const auto existing = cur->points[i];
    if (existing == loop_point) continue;
    if (existing && !existing->bad) {
      map->Replace(existing, loop_point);
    } else if (!loop_point->IsObservedBy(cur->id)) {
      cur->points[i] = loop_point;
      loop_point->AddObservation(cur, i);
      loop_point->ComputeDistinctiveDescriptor();
    }
    ++fused;
  }
  return fused;
}

struct EssentialGraph {
  optim::PoseGraphProblem problem;
  std::vector<KeyFramePtr> keyframes;
  std::map<uint64_t, int> index;
};

// ORB-SLAM2's OptimizeEssentialGraph graph: initial estimates `corrected` where given, edges
// measured on the poses before the correction (`uncorrected`), new loop links on the corrected
// ones.
EssentialGraph BuildEssentialGraph(const map::Map& map, const DetectedLoop& loop,
                                   const SimMap& corrected, const SimMap& uncorrected,
                                   const std::map<uint64_t, std::set<uint64_t>>& loop_connections,
                                   const std::set<std::pair<uint64_t, uint64_t>>& loop_edges,
                                   bool fix_scale) {
  EssentialGraph g;
  g.problem.fix_scale = fix_scale;
  SimMap before;  // measurements of the old edges
  for (const auto& [id, kf] : map.keyframes()) {
    if (kf->bad()) continue;
    g.index[id] = static_cast<int>(g.keyframes.size());
    g.keyframes.push_back(kf);
    auto c = corrected.find(id);
    g.problem.S_cam_world.push_back(c != corrected.end() ? c->second
                                                         : geometry::Sim3(kf->T_cam_world()));
    g.problem.fixed.push_back(id == loop.loop->id);
    auto u = uncorrected.find(id);
    before[id] = u != uncorrected.end() ? u->second : geometry::Sim3(kf->T_cam_world());
  }
  std::set<std::pair<uint64_t, uint64_t>> inserted;
  auto add = [&](uint64_t a, uint64_t b, const geometry::Sim3& S_a, const geometry::Sim3& S_b) {
    if (a == b || !g.index.count(a) || !g.index.count(b)) return;
    if (!inserted.insert({std::min(a, b), std::max(a, b)}).second) return;
    optim::PoseGraphProblem::Edge e;
    e.i = g.index[a];
    e.j = g.index[b];
    e.S_i_j = S_a * S_b.Inverse();
    g.problem.edges.push_back(e);
  };
  const auto& init = g.problem.S_cam_world;
  for (const auto& [id, others] : loop_connections) {
    if (!g.index.count(id)) continue;
    const KeyFramePtr& kf = g.keyframes[g.index[id]];
    for (uint64_t other : others) {
      const bool the_loop = id == loop.current->id && other == loop.loop->id;
      if (!the_loop && kf->Weight(other) < kEssentialMinWeight) continue;
      if (!g.index.count(other)) continue;
      add(id, other, init[g.index[id]], init[g.index[other]]);
    }
  }
  for (const auto& kf : g.keyframes) {
    if (auto parent = kf->parent()) add(kf->id, parent->id, before[kf->id], before[parent->id]);
    for (const auto& [a, b] : loop_edges) {
      if (a == kf->id && before.count(b)) add(a, b, before[a], before[b]);
    }
    for (const auto& [other, w] : kf->connection_weights()) {
      if (w < kEssentialMinWeight || other >= kf->id || !before.count(other)) continue;
      add(kf->id, other, before[kf->id], before[other]);
    }
  }
  return g;
}

}  // namespace

LoopCorrectionStats CorrectLoop(map::Map* map, const DetectedLoop& loop,
                                const std::set<std::pair<uint64_t, uint64_t>>& loop_edges,
                                const camera::PinholeCamera& camera, bool fix_scale) {
  LoopCorrectionStats stats;
  const KeyFramePtr& cur = loop.current;
  cur->UpdateConnections();
  const std::vector<KeyFramePtr> neighbourhood = CurrentNeighbourhood(*map, cur);
  // Sim(3) propagation: S_i_world corrected = (S_i_world * S_cur_world^-1) * S_cur_corrected.
  SimMap corrected, uncorrected;
  const geometry::Sim3 S_cur_before(cur->T_cam_world());
  for (const auto& kf : neighbourhood) {
    const geometry::Sim3 S_before(kf->T_cam_world());
    uncorrected[kf->id] = S_before;
    corrected[kf->id] = S_before * S_cur_before.Inverse() * loop.S_cur_world;
  }
  // Points move with the keyframe that first sees them in the neighbourhood; remembered for the
  // essential-graph step (ORB-SLAM2's mnCorrectedReference).
  std::map<uint64_t, uint64_t> corrected_by;
  for (const auto& kf : neighbourhood) {
    const geometry::Sim3 S_move = corrected[kf->id].Inverse() * uncorrected[kf->id];
    for (const auto& p : kf->points) {
      if (!p || p->bad || corrected_by.count(p->id)) continue;
      p->position = S_move * p->position;
      corrected_by[p->id] = kf->id;
    }
  }
  for (const auto& kf : neighbourhood) kf->SetPose(ToPose(corrected[kf->id]));
  for (const auto& kf : neighbourhood) {
    for (const auto& p : kf->points) {
      if (p && !p->bad) p->UpdateNormalAndDepth();
    }
  }
  stats.corrected_keyframes = static_cast<int>(neighbourhood.size());
  // Fusion: the current keyframe's matches, then the loop side's points into the neighbourhood.
  stats.fused_points = FuseCurrentMatches(map, loop);
  for (const auto& kf : neighbourhood) {
    if (!kf->bad()) stats.fused_points += Fuse(map, kf, loop.loop_points, camera, kLoopFuseRadius);
  }
  // New links: connections after fusion that neither were there before nor are neighbours.
  std::set<uint64_t> neighbour_ids;
  for (const auto& kf : neighbourhood) neighbour_ids.insert(kf->id);
  std::map<uint64_t, std::set<uint64_t>> loop_connections;
  for (const auto& kf : neighbourhood) {
    std::set<uint64_t> previous;
    for (const auto& n : kf->BestCovisibles(-1)) previous.insert(n->id);
    kf->UpdateConnections();
    for (const auto& [other, w] : kf->connection_weights()) {
      if (!previous.count(other) && !neighbour_ids.count(other))
        loop_connections[kf->id].insert(other);
    }
  }
  loop_connections[cur->id].insert(loop.loop->id);
  EssentialGraph g = BuildEssentialGraph(*map, loop, corrected, uncorrected, loop_connections,
                                         loop_edges, fix_scale);
  const optim::PoseGraphResult result = optim::OptimizePoseGraph(g.problem);
  stats.graph_vertices = static_cast<int>(g.keyframes.size());
  stats.graph_edges = static_cast<int>(g.problem.edges.size());
  stats.graph_initial_cost = result.initial_cost;
  stats.graph_final_cost = result.final_cost;
  // Every point moves with its reference keyframe (or the one that corrected it above).
  for (const auto& [id, p] : map->points()) {
    if (p->bad) continue;
    uint64_t ref_id;
    if (auto it = corrected_by.find(id); it != corrected_by.end()) {
      ref_id = it->second;
    } else if (auto ref = p->reference.lock()) {
      ref_id = ref->id;
    } else {
      continue;
    }
    auto k = g.index.find(ref_id);
    if (k == g.index.end()) continue;
    const size_t r = static_cast<size_t>(k->second);
    p->position = result.S_cam_world[r].Inverse() * (g.problem.S_cam_world[r] * p->position);
  }
  for (size_t k = 0; k < g.keyframes.size(); ++k) {
    g.keyframes[k]->SetPose(ToPose(result.S_cam_world[k]));
  }
  for (const auto& [id, p] : map->points()) {
    if (!p->bad) p->UpdateNormalAndDepth();
  }
  map->BumpGeneration();
  return stats;
}

GlobalBundleJob PrepareGlobalBundleAdjustment(const map::Map& map, const optim::CameraModel& camera,
                                              const optim::FarStereoWeighting& far) {
  GlobalBundleJob job;
  job.generation = map.generation();
  job.problem.camera = camera;
  std::map<uint64_t, int> pose_index;
  for (const auto& [id, kf] : map.keyframes()) {
    if (kf->bad()) continue;
    pose_index[id] = static_cast<int>(job.keyframe_ids.size());
    job.keyframe_ids.push_back(id);
    job.problem.T_cam_world.push_back(kf->T_cam_world());
    job.problem.pose_fixed.push_back(job.keyframe_ids.size() == 1);  // the oldest: the gauge
  }
  for (const auto& [id, p] : map.points()) {
    if (p->bad) continue;
    const int point = static_cast<int>(job.point_ids.size());
    bool any = false;
    for (const auto& [kf_id, obs] : p->observations()) {
      auto it = pose_index.find(kf_id);
      auto kf = obs.keyframe.lock();
      if (it == pose_index.end() || !kf) continue;
      const feature::Frame& f = kf->frame;
      const cv::KeyPoint& kp = f.keypoints_undistorted[obs.index];
      optim::BundleProblem::Edge e;
      e.pose = it->second;
      e.point = point;
      e.observation.pixel = Eigen::Vector2d(kp.pt.x, kp.pt.y);
      e.observation.u_right = f.u_right[obs.index];
      e.observation.inv_sigma2 = f.inv_level_sigma2[kp.octave];
      job.problem.edges.push_back(e);
      any = true;
    }
    if (!any) continue;
    job.point_ids.push_back(id);
    job.problem.points_world.push_back(p->position);
  }
  optim::WeighFarStereo(far, &job.problem);
  return job;
}

optim::BundleResult SolveGlobalBundleAdjustment(const GlobalBundleJob& job, int num_threads) {
  optim::BundleAdjusterOptions options;
  options.iterations_first = 10;  // ORB-SLAM2's global BA after a loop: 10 iterations
  options.iterations_second = 5;
  options.num_threads = num_threads;
  return optim::AdjustBundle(job.problem, options);
}

bool MergeGlobalBundleAdjustment(map::Map* map, const GlobalBundleJob& job,
                                 const optim::BundleResult& result) {
  if (map->generation() != job.generation) return false;
  // Corrected poses: the solved ones, then down the spanning tree for keyframes added meanwhile
  // (T_child_corrected = T_child_parent * T_parent_corrected, on the poses before the merge).
  std::map<uint64_t, geometry::SE3> after;
  std::deque<KeyFramePtr> queue;
  for (size_t k = 0; k < job.keyframe_ids.size(); ++k) {
    auto kf = map->keyframe(job.keyframe_ids[k]);
    if (!kf || kf->bad()) continue;
    after[kf->id] = result.T_cam_world[k];
    queue.push_back(kf);
  }
  while (!queue.empty()) {
    const KeyFramePtr kf = queue.front();
    queue.pop_front();
    for (uint64_t child_id : kf->children()) {
      auto child = map->keyframe(child_id);
      if (!child || child->bad() || after.count(child_id)) continue;
      after[child_id] = child->T_cam_world() * kf->T_world_cam() * after[kf->id];
      queue.push_back(child);
    }
  }
  std::map<uint64_t, size_t> point_index;
  for (size_t j = 0; j < job.point_ids.size(); ++j) point_index[job.point_ids[j]] = j;
  for (const auto& [id, p] : map->points()) {
    if (p->bad) continue;
    if (auto it = point_index.find(id); it != point_index.end()) {
      p->position = result.points_world[it->second];
      continue;
    }
    auto ref = p->reference.lock();
    if (!ref || !after.count(ref->id)) continue;
    p->position = after[ref->id].Inverse() * (ref->T_cam_world() * p->position);
  }
  for (const auto& [id, T] : after) map->keyframe(id)->SetPose(T);
  for (const auto& [id, p] : map->points()) {
    if (!p->bad) p->UpdateNormalAndDepth();
  }
  map->BumpGeneration();
  return true;
}

}  // namespace moslam::slam
