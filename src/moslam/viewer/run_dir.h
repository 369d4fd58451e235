// `moslam view RUN_DIR`: a finished run's outputs (runner/outputs.h) as one viewer picture, so
// that a run can be looked at afterwards and shared as one folder: the trajectory
// (CameraTrajectory.txt), the keyframes (KeyFrameTrajectory.txt), the numbers of summary.json,
// the data set's ground truth when its folder is still where summary.json says, and the final
// map when the folder holds one (`moslam run --save-map RUN_DIR/map.map`: every *.map file there
// is tried, the first good one drawn). The keyframe graph and the closed loops come as the live
// page's final picture has them: from the map file when there is one, else from
// keyframe_graph.json (runner/keyframe_graph.h), else (a folder written before that file was)
// the loops alone from summary.json.
#pragma once

#include <string>

#include "moslam/viewer/message.h"

namespace moslam::viewer {

struct RunView {
  Snapshot snapshot;
  RunPicture picture;
  std::string map_path;    // the map file drawn; empty: none
  std::string graph_from;  // the file the keyframe graph or the loops came from; empty: none
};

// InputError naming the file when RUN_DIR is no run folder (no summary.json or trajectory) or
// one of its files is broken (keyframe_graph.json included); a missing ground truth or map only
// leaves them out (a warning).
RunView LoadRunView(const std::string& run_dir);

}  // namespace moslam::viewer
