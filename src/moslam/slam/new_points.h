// New map points from a new keyframe and its covisible keyframes (ORB-SLAM2's
// LocalMapping::CreateNewMapPoints and ORBmatcher::SearchForTriangulation, Mur-Artal & Tardós
// 2017). Keypoints without a map point are matched by descriptor under the epipolar constraint,
// then triangulated (linear DLT) or, when the rays are nearly parallel but a stereo depth is
// available, back-projected from the view whose stereo parallax is larger. A point is kept only
// with positive depth in both views, a reprojection error under the chi-square bound in both, and
// consistent distance ratio versus pyramid-level ratio.
//
// Caller holds Map::mutex().
#pragma once

#include <memory>
#include <vector>

#include "moslam/camera/pinhole_camera.h"
#include "moslam/map/map.h"

namespace moslam::slam {

struct NewPointsOptions {
  int num_neighbours = 10;  // covisible keyframes searched (ORB-SLAM2: 10 stereo/RGB-D, 20 mono)
  void Check() const;       // InputError naming the field
};

std::vector<std::shared_ptr<map::MapPoint>> CreateNewMapPoints(
    map::Map* map, const std::shared_ptr<map::KeyFrame>& kf, const camera::PinholeCamera& camera,
    const NewPointsOptions& options = {});

// Epipolar matches between unmatched keypoints of kf1 and kf2 (pairs of keypoint indices):
// distance <= feature::kThLow, squared distance to the epipolar line of kf1's keypoint in kf2
// under 3.84 sigma^2 of kf2's level, each keypoint used once, rotation-consistent. Exposed for
// tests.
std::vector<std::pair<size_t, size_t>> SearchForTriangulation(const map::KeyFrame& kf1,
                                                              const map::KeyFrame& kf2,
                                                              const camera::PinholeCamera& camera);

}  // namespace moslam::slam
