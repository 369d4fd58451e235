#include "moslam/slam/system_view.h"

#include <algorithm>
#include <mutex>
#include <optional>
#include <unordered_set>
#include <utility>

namespace moslam::slam {
namespace {

// The points of `previous` (sorted by id) missing from `current` (sorted by id): a linear merge,
// so a view costs no hashing of the whole map.
void CollectErased(const std::vector<ViewMemory::Seen>& previous,
                   const std::vector<ViewMemory::Seen>& current, ViewMemory* memory) {
  size_t j = 0;
  for (const ViewMemory::Seen& p : previous) {
    while (j < current.size() && current[j].id < p.id) ++j;
    if (j < current.size() && current[j].id == p.id) continue;
    memory->erased.push_back(p);
    if (memory->erased.size() > memory->max_erased) memory->erased.pop_front();
  }
}

void FillKeypoints(const Tracker::CurrentFrame& frame, SystemView* view) {
  const size_t n = frame.frame.keypoints.size();
  view->keypoints.resize(2 * n);
  view->keypoint_kinds.resize(n);
  for (size_t i = 0; i < n; ++i) {
    view->keypoints[2 * i] = frame.frame.keypoints[i].pt.x;
    view->keypoints[2 * i + 1] = frame.frame.keypoints[i].pt.y;
    ViewKeypointKind kind = ViewKeypointKind::kUntracked;
    const bool outlier = i < frame.outlier.size() && frame.outlier[i];
    if (i < frame.points.size() && frame.points[i] && !outlier) {
      kind = ViewKeypointKind::kTracked;
    } else if (i < frame.frame.moving.size() && frame.frame.moving[i] != 0) {
      kind = ViewKeypointKind::kMoving;
    } else if (frame.frame.NearMovable(i)) {
      kind = ViewKeypointKind::kNearMask;
    }
    view->keypoint_kinds[i] = static_cast<uint8_t>(kind);
  }
}

// The keyframes' poses, and the edges between them by index into view->keyframes: the closed
// loops always, covisibility and spanning tree when asked. Under the map mutex.
void FillKeyFrames(const map::Map& map, const ViewRequest& request, SystemView* view) {
  view->keyframes.clear();
  view->loops.clear();
  view->covisibility.clear();
  view->spanning_tree.clear();
  view->has_graph = request.graph;
  std::vector<uint64_t> ids;  // of view->keyframes, ascending as the map keeps them
  for (const auto& [id, keyframe] : map.keyframes()) {
    if (keyframe->bad()) continue;
    ids.push_back(id);
    view->keyframes.push_back(keyframe->T_world_cam());
  }
  const auto index = [&ids](uint64_t id) -> std::optional<uint32_t> {
    const auto at = std::lower_bound(ids.begin(), ids.end(), id);
    if (at == ids.end() || *at != id) return std::nullopt;
    return static_cast<uint32_t>(at - ids.begin());
  };
  std::vector<std::pair<uint32_t, uint32_t>> loops;  // (current, loop): sorted, newest last
  for (const auto& [a, b] : map.loop_edges()) {
    const auto ia = index(a), ib = index(b);
    if (a > b && ia && ib) loops.emplace_back(*ia, *ib);
  }
  std::sort(loops.begin(), loops.end());
  for (const auto& [current, loop] : loops) view->loops.insert(view->loops.end(), {loop, current});
  if (!request.graph) return;
  for (const auto& [id, keyframe] : map.keyframes()) {
    const auto i = index(id);
    if (!i) continue;
    for (const auto& [other, weight] : keyframe->connection_weights()) {
      const auto j = index(other);
      if (j && weight >= kViewCovisibilityMinWeight) {
        view->covisibility.insert(view->covisibility.end(),
                                  {*i, *j, static_cast<uint32_t>(weight)});
      }
    }
    const std::shared_ptr<map::KeyFrame> parent = keyframe->parent();
    const auto p = parent ? index(parent->id) : std::nullopt;
    if (p) view->spanning_tree.insert(view->spanning_tree.end(), {*i, *p});
  }
}

}  // namespace

void FillSystemView(const map::Map& map, const Tracker& tracker, const ViewRequest& request,
                    const std::vector<cv::Point2f>& rejected, ViewMemory* memory,
                    SystemView* view) {
  const Tracker::CurrentFrame& frame = tracker.viewed_frame();
  FillKeypoints(frame, view);
  view->rejected_keypoints.clear();
  for (const cv::Point2f& p : rejected)
    view->rejected_keypoints.insert(view->rejected_keypoints.end(), {p.x, p.y});
  std::vector<ViewMemory::Seen> current;
  view->points.clear();
  view->point_states.clear();
  {
    std::lock_guard<std::mutex> lock(map.mutex());
    // Points of the two newest keyframes are on probation (local mapping's recent points).
    const uint64_t newest = map.next_keyframe_id();
    const uint64_t recent_from = newest >= 2 ? newest - 2 : 0;
    std::unordered_set<const map::MapPoint*> local, tracked;
    for (const auto& p : tracker.local_points()) local.insert(p.get());
    for (const auto& p : frame.points) tracked.insert(p.get());
    current.reserve(map.points().size());
    view->point_states.reserve(map.points().size());
    for (const auto& [id, point] : map.points()) {
      const Eigen::Vector3f x = point->position.cast<float>();
      current.push_back(
          {id, x.x(), x.y(), x.z(), point->movable_evidence > 0 || point->free_space_evidence > 0});
      ViewPointState state = ViewPointState::kMap;
      if (tracked.count(point.get()) > 0) {
        state = ViewPointState::kTracked;
      } else if (point->first_keyframe_id >= recent_from) {
        state = ViewPointState::kNew;
      } else if (local.count(point.get()) > 0) {
        state = ViewPointState::kLocal;
      }
      view->point_states.push_back(static_cast<uint8_t>(state));
    }
    FillKeyFrames(map, request, view);
  }
  CollectErased(memory->seen, current, memory);
  memory->seen = std::move(current);
  view->points.reserve(3 * (memory->seen.size() + memory->erased.size()));
  for (const ViewMemory::Seen& p : memory->seen) {
    view->points.insert(view->points.end(), {p.x, p.y, p.z});
  }
  for (const ViewMemory::Seen& p : memory->erased) {
    view->points.insert(view->points.end(), {p.x, p.y, p.z});
    view->point_states.push_back(static_cast<uint8_t>(
        p.movable_evidence ? ViewPointState::kErasedMovable : ViewPointState::kErasedOther));
  }
}

}  // namespace moslam::slam
