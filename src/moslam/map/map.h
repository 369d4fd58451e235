// The map (ORB-SLAM2's Map, Mur-Artal & Tardós 2017): it owns keyframes and map points
// (shared_ptr; back-references elsewhere are weak_ptr or ids) and the one mutex that guards them.
//
// Locking design (one mutex, provably free of lock-order problems): every mutable field of
// KeyFrame, MapPoint and Map is read and written only while Map::mutex() is held. Tracking takes
// it for each of its map-reading steps and for keyframe creation; local mapping takes it for each
// modification step. Bundle adjustment copies the problem into plain structs under the lock,
// solves without it, and writes the result back under it, skipping entities that were erased in
// between. No other mutex is ever taken while holding this one, except the keyframe queue's
// (which never calls back), so there is no lock-order cycle.
//
// Loop closing (slam/loop_closer.h) holds the mutex for its whole correction (Sim(3)
// propagation, fusion, essential-graph optimization), so tracking and local mapping see the map
// either before or after it, never half-corrected; it then bumps generation(). Local bundle
// adjustment records the generation when it copies its problem out and drops its result when the
// generation changed before the write-back (its poses would undo the correction). The global
// bundle adjustment after a loop is copied, solved in its own thread and merged the same way: a
// merge whose copy is older than the current generation (a second loop closed meanwhile) is
// dropped.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <utility>
#include <vector>

#include "moslam/map/keyframe.h"
#include "moslam/map/map_point.h"

namespace moslam::map {

class Map {
 public:
  std::mutex& mutex() const { return mutex_; }

  // Ids are unique and increasing over the run; the first keyframe gets id 0.
  std::shared_ptr<KeyFrame> CreateKeyFrame(feature::Frame frame, const geometry::SE3& T_cam_world);
  std::shared_ptr<MapPoint> CreateMapPoint(const Eigen::Vector3d& position,
                                           const std::shared_ptr<KeyFrame>& reference);

  // Sets the point bad, drops its observations from the keyframes and removes it.
  void EraseMapPoint(const std::shared_ptr<MapPoint>& point);
  // SetBad on the keyframe, then removes it and the points it orphaned, and tells the erase
  // listener.
  void EraseKeyFrame(const std::shared_ptr<KeyFrame>& keyframe);
  // Called by EraseKeyFrame (map mutex held) for every erased keyframe, so that indexes of
  // keyframes kept outside the map (slam's keyframe database) drop it, as ORB-SLAM2's
  // KeyFrame::SetBadFlag erases it from its KeyFrameDatabase. Must not lock the map mutex.
  void SetKeyFrameEraseListener(std::function<void(const KeyFrame&)> listener) {
    erase_listener_ = std::move(listener);
  }
  // Fuses `old_point` into `new_point`: observations move (unless the keyframe already sees
  // new_point), counters add up, old_point is erased and remembers its replacement.
  void Replace(const std::shared_ptr<MapPoint>& old_point,
               const std::shared_ptr<MapPoint>& new_point);

  // Loop edges (ORB-SLAM2's KeyFrame::mspLoopEdges): both directions of each closed loop's
  // (current, loop) keyframe pair. Kept in the map rather than in loop closing so that a saved map
  // carries them (mapio/map_file.h) and the essential graph of a later loop still holds them.
  const std::set<std::pair<uint64_t, uint64_t>>& loop_edges() const { return loop_edges_; }
  void AddLoopEdge(uint64_t a, uint64_t b) {
    loop_edges_.insert({a, b});
    loop_edges_.insert({b, a});
  }

  // --- restoring a saved map (mapio/map_file.h) ---
  // A keyframe / point with the id it was saved with; the id must be unused (CHECK), and the
  // next ids continue after the largest one restored.
  std::shared_ptr<KeyFrame> RestoreKeyFrame(uint64_t id, feature::Frame frame,
                                            const geometry::SE3& T_cam_world);
  std::shared_ptr<MapPoint> RestoreMapPoint(uint64_t id, const Eigen::Vector3d& position,
                                            const std::shared_ptr<KeyFrame>& reference,
                                            uint64_t first_keyframe_id);
  // The id counters and generation as saved (each at least what the restored entities need).
  void RestoreCounters(uint64_t next_keyframe_id, uint64_t next_point_id, uint64_t generation);
  uint64_t next_point_id() const { return next_point_id_; }

  const std::map<uint64_t, std::shared_ptr<KeyFrame>>& keyframes() const { return keyframes_; }
  const std::map<uint64_t, std::shared_ptr<MapPoint>>& points() const { return points_; }
  std::shared_ptr<KeyFrame> keyframe(uint64_t id) const;
  uint64_t next_keyframe_id() const { return next_keyframe_id_; }
  // keyframes().size() and points().size() as of the last change, readable without the lock:
  // the tracking thread reports them after every frame (FrameReport) without waiting for local
  // mapping to let go of the map.
  size_t num_keyframes() const { return num_keyframes_.load(std::memory_order_relaxed); }
  size_t num_points() const { return num_points_.load(std::memory_order_relaxed); }

  // Bumped by every global move of poses and points (loop correction, the merge of a global
  // bundle adjustment). A step that copied poses out under an older generation and solved
  // without the lock (local bundle adjustment) must drop its result instead of writing stale
  // poses over the correction.
  uint64_t generation() const { return generation_; }
  void BumpGeneration() { ++generation_; }

 private:
  mutable std::mutex mutex_;
  std::map<uint64_t, std::shared_ptr<KeyFrame>> keyframes_;
  std::map<uint64_t, std::shared_ptr<MapPoint>> points_;
  std::atomic<size_t> num_keyframes_{0}, num_points_{0};  // num_keyframes(), num_points()
  void CountEntities() {
    num_keyframes_.store(keyframes_.size(), std::memory_order_relaxed);
    num_points_.store(points_.size(), std::memory_order_relaxed);
  }
  uint64_t next_keyframe_id_ = 0;
  uint64_t next_point_id_ = 0;
  uint64_t generation_ = 0;
  std::set<std::pair<uint64_t, uint64_t>> loop_edges_;
  std::function<void(const KeyFrame&)> erase_listener_;
};

}  // namespace moslam::map
