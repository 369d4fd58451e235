// A keyframe (ORB-SLAM2's KeyFrame, Mur-Artal & Tardós 2017): the frame's features (kept whole,
// including descriptors, so that a bag-of-words index can be built later), its pose, the map
// point matched to each keypoint, covisibility edges (weight = shared map points) and its place in
// the spanning tree (parent = the most covisible earlier keyframe).
//
// Locking: `id`, `frame` and `timestamp` are immutable after construction; every other field is
// guarded by the owning Map's mutex (map/map.h): hold Map::mutex() for every call below.
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <vector>

#include "moslam/feature/frame.h"
#include "moslam/geometry/se3.h"
#include "moslam/vocab/bow.h"

namespace moslam::map {

class MapPoint;

class KeyFrame : public std::enable_shared_from_this<KeyFrame> {
 public:
  KeyFrame(uint64_t id, feature::Frame frame, const geometry::SE3& T_cam_world);

  const uint64_t id;
  const feature::Frame frame;

  const geometry::SE3& T_cam_world() const { return T_cam_world_; }
  geometry::SE3 T_world_cam() const { return T_cam_world_.Inverse(); }
  Eigen::Vector3d CameraCenter() const { return T_world_cam_.translation(); }
  void SetPose(const geometry::SE3& T_cam_world);

  // Bag of words of frame.descriptors and its direct index (vocab/bow.h), set once by whoever
  // holds the vocabulary (local mapping, on insertion) before the keyframe enters the keyframe
  // database; empty when the system runs without a vocabulary.
  vocab::BowVector bow;
  vocab::FeatureVector bow_features;

  // Per keypoint, nullptr when unmatched.
  std::vector<std::shared_ptr<MapPoint>> points;
  // Points that are set and not bad, with at least `min_observations` observations.
  int TrackedMapPoints(int min_observations) const;
  // Median depth of the keyframe's map points in its camera (ORB-SLAM2's ComputeSceneMedianDepth).
  double MedianDepth() const;

  // --- covisibility graph ---
  // Recounts the points shared with other keyframes, keeps edges with weight >= 15 (or the best
  // one when none reaches it), updates the other side of each edge, and on the first call sets
  // the spanning-tree parent to the most covisible earlier keyframe (ORB-SLAM2's
  // UpdateConnections).
  void UpdateConnections();
  // Keyframes ordered by decreasing weight (ties by increasing id), at most n (n < 0: all).
  std::vector<std::shared_ptr<KeyFrame>> BestCovisibles(int n) const;
  int Weight(uint64_t other_id) const;
  void AddConnection(const std::shared_ptr<KeyFrame>& other, int weight);
  void EraseConnection(uint64_t other_id);
  const std::map<uint64_t, int>& connection_weights() const { return weights_; }

  // --- spanning tree ---
  std::shared_ptr<KeyFrame> parent() const { return parent_.lock(); }
  const std::set<uint64_t>& children() const { return children_; }
  void SetParent(const std::shared_ptr<KeyFrame>& parent);
  // True until UpdateConnections has chosen a parent (the first keyframe keeps it); saved with
  // the map so that a restored keyframe chooses its parent the same way.
  bool first_connection() const { return first_connection_; }
  void RestoreFirstConnection(bool first) { first_connection_ = first; }

  // --- erasure ---
  bool bad() const { return bad_; }
  // Pose relative to the parent, kept when the keyframe is erased so that frames referring to it
  // still get a pose (ORB-SLAM2's mTcp).
  const geometry::SE3& T_cam_parent() const { return T_cam_parent_; }
  // Marks the keyframe bad: drops its observations from its points and its edges, and reconnects
  // its children in the spanning tree to the most covisible candidate (ORB-SLAM2's SetBadFlag).
  // Points left with too few observations are set bad and returned for the map to erase. The
  // first keyframe (no parent) is never erased.
  std::vector<std::shared_ptr<MapPoint>> SetBad(
      const std::map<uint64_t, std::shared_ptr<KeyFrame>>& all_keyframes);

 private:
  void RebuildOrder();

  geometry::SE3 T_cam_world_;
  geometry::SE3 T_world_cam_;
  std::map<uint64_t, std::weak_ptr<KeyFrame>> connected_;
  std::map<uint64_t, int> weights_;
  std::vector<std::weak_ptr<KeyFrame>> ordered_;  // by weight
  bool first_connection_ = true;
  std::weak_ptr<KeyFrame> parent_;
  std::set<uint64_t> children_;
  bool bad_ = false;
  geometry::SE3 T_cam_parent_;
};

}  // namespace moslam::map
