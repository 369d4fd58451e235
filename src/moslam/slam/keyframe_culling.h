// Redundant keyframe culling (ORB-SLAM2's LocalMapping::KeyFrameCulling, Mur-Artal & Tardós
// 2017): a covisible keyframe of the new one is erased when more than 90 % of its map points are
// seen by at least three other keyframes at the same or a finer scale. For stereo/RGB-D only its
// close points count (depth in (0, close_depth]), since far points are poorly constrained. The
// first keyframe is never erased.
//
// Caller holds Map::mutex().
#pragma once

#include <memory>

#include "moslam/map/map.h"

namespace moslam::slam {

// Whether `kf` is redundant by the rule above (close_depth_m <= 0: every point counts).
bool IsRedundant(const map::KeyFrame& kf, const map::Map& map, double close_depth_m);

// Tests kf's covisible keyframes and erases the redundant ones; returns how many.
int CullRedundantKeyFrames(map::Map* map, const std::shared_ptr<map::KeyFrame>& kf,
                           double close_depth_m);

}  // namespace moslam::slam
