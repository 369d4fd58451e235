// Fusion of duplicated map points (ORB-SLAM2's ORBmatcher::Fuse and
// LocalMapping::SearchInNeighbors, Mur-Artal & Tardós 2017): points are projected into a keyframe
// and matched to the keypoint with the closest descriptor near the projection (level and
// chi-square checks); a keypoint that already has a point gets the two fused (the one with more
// observations survives), otherwise it gains the observation.
//
// Caller holds Map::mutex().
#pragma once

#include <memory>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/map/map.h"

namespace moslam::slam {

// Projects `points` into `kf` (search radius `radius_px` times the predicted level's scale).
// Returns the number of points fused or added.
int Fuse(map::Map* map, const std::shared_ptr<map::KeyFrame>& kf,
         const std::vector<std::shared_ptr<map::MapPoint>>& points,
         const camera::PinholeCamera& camera, float radius_px = 3.0f);

// Fuses kf's points into its neighbours (best `num_neighbours` covisibles and each one's best 5)
// and theirs into kf, then refreshes kf's points' descriptors and normals and its connections.
void SearchInNeighbors(map::Map* map, const std::shared_ptr<map::KeyFrame>& kf,
                       const camera::PinholeCamera& camera, int num_neighbours = 10);

}  // namespace moslam::slam
