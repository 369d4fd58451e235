#include "moslam/map/keyframe_graph.h"

#include <algorithm>
#include <optional>
#include <utility>

namespace moslam::map {

IndexedKeyFrameGraph IndexKeyFrameGraph(const Map& map, bool with_graph, int min_weight) {
  IndexedKeyFrameGraph out;
  for (const auto& [id, keyframe] : map.keyframes()) {
    if (keyframe->bad()) continue;
    out.ids.push_back(id);
    out.poses.push_back(keyframe->T_world_cam());
  }
  // Binary search: the ids are ascending as the map keeps them, and an edge to a keyframe that is
  // gone (bad, erased) has no index and is left out.
  const auto index = [&out](uint64_t id) -> std::optional<uint32_t> {
    const auto at = std::lower_bound(out.ids.begin(), out.ids.end(), id);
    if (at == out.ids.end() || *at != id) return std::nullopt;
    return static_cast<uint32_t>(at - out.ids.begin());
  };
  std::vector<std::pair<uint32_t, uint32_t>> loops;  // (current, loop): the newest loop last
  for (const auto& [a, b] : map.loop_edges()) {
    const auto ia = index(a), ib = index(b);
    if (a > b && ia && ib) loops.emplace_back(*ia, *ib);  // each loop once, from its current end
  }
  std::sort(loops.begin(), loops.end());
  for (const auto& [current, loop] : loops) out.loops.insert(out.loops.end(), {loop, current});
  if (!with_graph) return out;
  for (const auto& [id, keyframe] : map.keyframes()) {
    const auto i = index(id);
    if (!i) continue;
    for (const auto& [other, weight] : keyframe->connection_weights()) {
      const auto j = index(other);
      if (j && weight >= min_weight) {
        out.covisibility.insert(out.covisibility.end(), {*i, *j, static_cast<uint32_t>(weight)});
      }
    }
    const std::shared_ptr<KeyFrame> parent = keyframe->parent();
    const auto p = parent ? index(parent->id) : std::nullopt;
    if (p) out.spanning_tree.insert(out.spanning_tree.end(), {*i, *p});
  }
  return out;
}

}  // namespace moslam::map
