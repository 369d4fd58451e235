#include "moslam/slam/system_view.h"

#include <mutex>
#include <unordered_set>
#include <utility>

#include "moslam/map/keyframe_graph.h"

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
// loops always, covisibility and spanning tree when asked (map/keyframe_graph.h, which `moslam
// view` uses on a saved map too). Under the map mutex.
void FillKeyFrames(const map::Map& map, const ViewRequest& request, SystemView* view) {
  map::IndexedKeyFrameGraph graph =
      map::IndexKeyFrameGraph(map, request.graph, kViewCovisibilityMinWeight);
  view->keyframes = std::move(graph.poses);
  view->loops = std::move(graph.loops);
  view->covisibility = std::move(graph.covisibility);
  view->spanning_tree = std::move(graph.spanning_tree);
  view->has_graph = request.graph;
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
