// A 3D landmark (ORB-SLAM2's MapPoint, Mur-Artal & Tardós 2017): world position, the keyframes
// that observe it (keyframe id -> keypoint index), its reference keyframe, mean viewing direction,
// the scale-invariance distance range [min_distance, max_distance] and a representative
// descriptor (the observation descriptor with the least median distance to the others).
//
// Locking: every mutable field is guarded by the owning Map's mutex (map/map.h); callers hold
// Map::mutex() for every call below. Only `id` is immutable.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <utility>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace moslam::map {

class KeyFrame;

class MapPoint {
 public:
  MapPoint(uint64_t id, const Eigen::Vector3d& position, const std::shared_ptr<KeyFrame>& ref,
           uint64_t first_keyframe_id);

  const uint64_t id;
  Eigen::Vector3d position;
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // mean unit viewing direction (world)
  float min_distance = 0.0f;                         // metres, scale-invariance range
  float max_distance = 0.0f;
  cv::Mat descriptor;  // 1 x 32 CV_8U
  std::weak_ptr<KeyFrame> reference;
  uint64_t first_keyframe_id = 0;
  bool bad = false;
  // Set when fused into another point (Map::Replace), so that trackers holding this one follow.
  std::weak_ptr<MapPoint> replaced_by;
  // Tracking statistics for culling (ORB-SLAM2's mnVisible / mnFound).
  int visible = 1;
  int found = 1;
  // Frames whose movable-object mask covered the point where it projects, and RGB-D frames
  // whose depth showed free space in front of where it should be seen (slam/movable_points.h);
  // past a threshold the point is erased.
  int movable_evidence = 0;
  int free_space_evidence = 0;

  struct Observation {
    std::weak_ptr<KeyFrame> keyframe;
    size_t index = 0;
  };
  // Ordered by keyframe id so that every pass over them is deterministic.
  const std::map<uint64_t, Observation>& observations() const { return observations_; }
  // Stereo observations count twice (ORB-SLAM2's nObs).
  int num_observations() const { return num_obs_; }
  bool IsObservedBy(uint64_t keyframe_id) const { return observations_.count(keyframe_id) > 0; }
  // -1 when not observed by that keyframe.
  int IndexIn(uint64_t keyframe_id) const;

  void AddObservation(const std::shared_ptr<KeyFrame>& keyframe, size_t index);
  // Returns true when the point is left with too few observations (<= 2) and should be erased.
  bool EraseObservation(uint64_t keyframe_id);

  float FoundRatio() const { return static_cast<float>(found) / static_cast<float>(visible); }

  // Recomputes the representative descriptor from the observing keyframes.
  void ComputeDistinctiveDescriptor();
  // Recomputes the normal and the distance range from the observations and the reference
  // keyframe (ORB-SLAM2's UpdateNormalAndDepth).
  void UpdateNormalAndDepth();
  // Pyramid level at which a point at `distance` is expected to be detected.
  int PredictScale(float distance, float log_scale_factor, int num_levels) const;

 private:
  std::map<uint64_t, Observation> observations_;
  int num_obs_ = 0;
};

}  // namespace moslam::map
