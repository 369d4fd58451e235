// Map-level matchers of loop closing (ORB-SLAM2's ORBmatcher::SearchByBoW(KF, KF),
// SearchBySim3 and SearchByProjection(KF, Scw, ...), Mur-Artal & Tardós 2017).
//
// Matches are returned per keypoint of the first keyframe: the matched map point of the other
// keyframe (or of the projected set), nullptr when unmatched. Caller holds Map::mutex().
#pragma once

#include <memory>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/geometry/sim3.h"
#include "moslam/map/map.h"

namespace moslam::slam {

using PointMatches = std::vector<std::shared_ptr<map::MapPoint>>;  // per keypoint of kf1

// Descriptor matches between the map points of kf1 and kf2 (each keypoint with a good point),
// nearest neighbour with a ratio test and the rotation-consistency check. Stands in for
// ORB-SLAM2's SearchByBoW(KF, KF) (ratio 0.75 in loop closing): brute force over the points
// only, as tracking's reference-keyframe search does here, so it needs no vocabulary.
PointMatches MatchKeyFramePoints(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                 float ratio = 0.75f);

// More matches given S_12 (maps camera 2 into camera 1): kf1's points projected into kf2 and
// kf2's into kf1, each matched to the best keypoint near the projection (descriptor distance <=
// feature::kThHigh); only mutual matches are kept, and only where `matches` has none yet.
// Returns the number added.
int SearchBySim3(const map::KeyFrame& kf1, const map::KeyFrame& kf2, const geometry::Sim3& S_12,
                 const camera::PinholeCamera& camera, float radius_px, PointMatches* matches);

// Projects `points` into kf with the similarity S_cam_world (a corrected pose) and fills the
// keypoints of `matched` that are still empty with the best point (distance <= feature::kThLow),
// checking scale range and viewing angle. Returns the number added.
int SearchByProjectionSim3(const map::KeyFrame& kf, const geometry::Sim3& S_cam_world,
                           const std::vector<std::shared_ptr<map::MapPoint>>& points,
                           const camera::PinholeCamera& camera, float radius_px,
                           PointMatches* matched);

}  // namespace moslam::slam
