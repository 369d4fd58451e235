// keyframe_graph.json, which `moslam run` leaves beside KeyFrameTrajectory.txt: the final
// keyframe graph the live viewer draws (the covisibility edges of at least
// slam::kViewCovisibilityMinWeight shared points, the spanning tree and the closed loops), so
// that `moslam view RUN_DIR` shows it for a run saved without a map file. The edges index the
// keyframes in the order of KeyFrameTrajectory.txt (the map's good keyframes by id, both written
// after Tracker::Finish); the file repeats their timestamps so a reader can check that they match.
//
//   {"format": "moslam keyframe graph", "version": 1, "min_covisibility_weight": 100,
//    "timestamps": [t, ...],             one per keyframe
//    "covisibility": [[i, j, weight], ...], each edge once, i < j
//    "spanning_tree": [[child, parent], ...],
//    "loops": [[loop, current], ...]}     newest loop last
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "moslam/eval/trajectory.h"
#include "moslam/runner/tracker.h"

namespace moslam::runner {

// As slam::SystemView holds it (covisibility in both directions), so it goes into a view as is.
struct KeyFrameGraph {
  std::vector<double> timestamps;
  std::vector<uint32_t> covisibility;   // i, j, weight, each edge both ways
  std::vector<uint32_t> spanning_tree;  // child, parent
  std::vector<uint32_t> loops;          // loop, current
};

// The tracker's graph after Finish (Tracker::View with the graph on), for the keyframes of
// `keyframes` (Tracker::KeyFrameTrajectory); nullopt when the tracker shows none (fakes) or its
// keyframes are not those.
std::optional<KeyFrameGraph> FinalKeyFrameGraph(Tracker& tracker,
                                                const eval::Trajectory& keyframes);

// InputError naming the file when it cannot be written, read or is not such a file (an index
// out of range, a malformed edge).
void WriteKeyFrameGraph(const KeyFrameGraph& graph, const std::string& path);
KeyFrameGraph ReadKeyFrameGraph(const std::string& path);

}  // namespace moslam::runner
