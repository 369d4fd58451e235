// The keyframe graph as a viewer draws it: the map's good keyframes in id order and the edges
// between them by index into that order, so that a picture of the graph needs no ids. Shared by
// the live viewer (slam::System::View) and `moslam view` of a saved map (viewer/run_dir.h), so a
// finished run shows the same edges as the live page did.
#pragma once

#include <cstdint>
#include <vector>

#include "moslam/geometry/se3.h"
#include "moslam/map/map.h"

namespace moslam::map {

struct IndexedKeyFrameGraph {
  std::vector<uint64_t> ids;         // the good keyframes, ascending
  std::vector<geometry::SE3> poses;  // T_world_cam of each, as `ids`
  // Closed loops always: loop, current per loop, ordered by the current keyframe (newest last).
  std::vector<uint32_t> loops;
  // With `with_graph` only: i, j, weight per covisibility edge of at least `min_weight` shared
  // points, each pair in both directions; child, parent per keyframe of the spanning tree.
  std::vector<uint32_t> covisibility;
  std::vector<uint32_t> spanning_tree;
};

// The caller holds map.mutex() when another thread may change the map.
IndexedKeyFrameGraph IndexKeyFrameGraph(const Map& map, bool with_graph, int min_weight);

}  // namespace moslam::map
