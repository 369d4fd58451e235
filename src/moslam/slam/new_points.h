// New map points from a new keyframe and its covisible keyframes (ORB-SLAM2's
// LocalMapping::CreateNewMapPoints and ORBmatcher::SearchForTriangulation, Mur-Artal & Tardós
// 2017). Keypoints without a map point are matched by descriptor under the epipolar constraint,
// then triangulated (linear DLT) or, when the rays are nearly parallel but a stereo depth is
// available, back-projected from the view whose stereo parallax is larger. A point is kept only
// with positive depth in both views, a reprojection error under the chi-square bound in both, and
// consistent distance ratio versus pyramid-level ratio.
//
// Caller holds Map::mutex() for every function below except RunTriangulationSearch, which works
// on a snapshot: local mapping runs the expensive epipolar search without the lock, so tracking
// is not held up (Prepare under the lock, Run without it, CreatePointsFromMatches under it).
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

// Prepare + Run + CreatePointsFromMatches in one call.
std::vector<std::shared_ptr<map::MapPoint>> CreateNewMapPoints(
    map::Map* map, const std::shared_ptr<map::KeyFrame>& kf, const camera::PinholeCamera& camera,
    const NewPointsOptions& options = {});

// What the epipolar search needs, copied under the lock: poses and which keypoints are free.
struct TriangulationSearch {
  std::shared_ptr<map::KeyFrame> kf;
  geometry::SE3 T_cam_world;
  std::vector<bool> free;  // per keypoint of kf: no (good) map point
  struct Neighbour {
    std::shared_ptr<map::KeyFrame> kf;
    geometry::SE3 T_cam_world;
    std::vector<bool> free;
    std::vector<std::pair<size_t, size_t>> matches;  // (kf keypoint, neighbour keypoint)
  };
  std::vector<Neighbour> neighbours;
};
TriangulationSearch PrepareTriangulationSearch(const std::shared_ptr<map::KeyFrame>& kf,
                                               const camera::PinholeCamera& camera,
                                               const NewPointsOptions& options = {});
// Without the lock: reads only the snapshot and the keyframes' immutable frames.
void RunTriangulationSearch(TriangulationSearch* search, const camera::PinholeCamera& camera);
// Triangulates the matches with the keyframes' current poses, skipping keypoints that got a
// point meanwhile and keyframes erased meanwhile.
std::vector<std::shared_ptr<map::MapPoint>> CreatePointsFromMatches(
    map::Map* map, const TriangulationSearch& search, const camera::PinholeCamera& camera);

// Epipolar matches between unmatched keypoints of kf1 and kf2 (pairs of keypoint indices):
// distance <= feature::kThLow, squared distance to the epipolar line of kf1's keypoint in kf2
// under 3.84 sigma^2 of kf2's level, each keypoint used once, rotation-consistent. When both
// keyframes carry a bag-of-words direct index, only keypoints under the same vocabulary node
// are compared (ORB-SLAM2); otherwise every free keypoint of kf2 is a candidate. Exposed for
// tests.
std::vector<std::pair<size_t, size_t>> SearchForTriangulation(const map::KeyFrame& kf1,
                                                              const map::KeyFrame& kf2,
                                                              const camera::PinholeCamera& camera);
// The same on plain data (free*: keypoints that may be matched).
std::vector<std::pair<size_t, size_t>> SearchForTriangulation(
    const feature::Frame& frame1, const geometry::SE3& T_cam1_world, const std::vector<bool>& free1,
    const feature::Frame& frame2, const geometry::SE3& T_cam2_world, const std::vector<bool>& free2,
    const camera::PinholeCamera& camera, const vocab::FeatureVector* features1 = nullptr,
    const vocab::FeatureVector* features2 = nullptr);

}  // namespace moslam::slam
