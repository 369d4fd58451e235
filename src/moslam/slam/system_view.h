// System::View's work (system.h, SystemView): copies of the map and of the tracker's last frame
// for a viewer, and the memory of which points have gone since the previous view.
#pragma once

#include <cstdint>
#include <deque>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/map/map.h"
#include "moslam/slam/system.h"
#include "moslam/slam/tracker.h"

namespace moslam::slam {

// What one view remembers for the next: the points it saw (sorted by id, as the map keeps them)
// and the points erased since views began, newest last.
struct ViewMemory {
  struct Seen {
    uint64_t id = 0;
    float x = 0, y = 0, z = 0;
    bool movable_evidence = false;  // a mask or free space had spoken against it
  };
  std::vector<Seen> seen;
  std::deque<Seen> erased;
  size_t max_erased = 20000;
};

// Fills *view from the map (locks its mutex) and the tracker's last frame (tracking thread only);
// `rejected`: the keypoints the last frame's mask took away (level-0 pixels; empty when nobody
// watched while it was extracted).
void FillSystemView(const map::Map& map, const Tracker& tracker, const ViewRequest& request,
                    const std::vector<cv::Point2f>& rejected, ViewMemory* memory, SystemView* view);

}  // namespace moslam::slam
