#include "moslam/map/map.h"

#include <algorithm>
#include <utility>

#include "moslam/util/check.h"

namespace moslam::map {

std::shared_ptr<KeyFrame> Map::CreateKeyFrame(feature::Frame frame,
                                              const geometry::SE3& T_cam_world) {
  auto kf = std::make_shared<KeyFrame>(next_keyframe_id_++, std::move(frame), T_cam_world);
  keyframes_[kf->id] = kf;
  CountEntities();
  return kf;
}

std::shared_ptr<MapPoint> Map::CreateMapPoint(const Eigen::Vector3d& position,
                                              const std::shared_ptr<KeyFrame>& reference) {
  auto p = std::make_shared<MapPoint>(next_point_id_++, position, reference, reference->id);
  points_[p->id] = p;
  CountEntities();
  return p;
}

void Map::EraseMapPoint(const std::shared_ptr<MapPoint>& point) {
  if (!point) return;
  point->bad = true;
  for (const auto& [kf_id, obs] : point->observations()) {
    auto kf = obs.keyframe.lock();
    if (kf && obs.index < kf->points.size() && kf->points[obs.index] == point) {
      kf->points[obs.index] = nullptr;
    }
  }
  points_.erase(point->id);
  CountEntities();
}

void Map::EraseKeyFrame(const std::shared_ptr<KeyFrame>& keyframe) {
  if (!keyframe || !keyframe->parent()) return;  // the first keyframe stays
  for (const auto& p : keyframe->SetBad(keyframes_)) EraseMapPoint(p);
  keyframes_.erase(keyframe->id);
  CountEntities();
  if (erase_listener_) erase_listener_(*keyframe);
}

void Map::Replace(const std::shared_ptr<MapPoint>& old_point,
                  const std::shared_ptr<MapPoint>& new_point) {
  if (!old_point || !new_point || old_point == new_point || old_point->bad) return;
  const auto observations = old_point->observations();
  for (const auto& [kf_id, obs] : observations) {
    auto kf = obs.keyframe.lock();
    if (!kf) continue;
    if (!new_point->IsObservedBy(kf_id)) {
      kf->points[obs.index] = new_point;
      new_point->AddObservation(kf, obs.index);
    } else {
      kf->points[obs.index] = nullptr;
    }
  }
  new_point->found += old_point->found;
  new_point->visible += old_point->visible;
  new_point->ComputeDistinctiveDescriptor();
  old_point->replaced_by = new_point;
  old_point->bad = true;
  points_.erase(old_point->id);
  CountEntities();
}

std::shared_ptr<KeyFrame> Map::RestoreKeyFrame(uint64_t id, feature::Frame frame,
                                               const geometry::SE3& T_cam_world) {
  MOSLAM_CHECK(keyframes_.count(id) == 0) << "keyframe " << id << " restored twice";
  auto kf = std::make_shared<KeyFrame>(id, std::move(frame), T_cam_world);
  keyframes_[id] = kf;
  CountEntities();
  next_keyframe_id_ = std::max(next_keyframe_id_, id + 1);
  return kf;
}

std::shared_ptr<MapPoint> Map::RestoreMapPoint(uint64_t id, const Eigen::Vector3d& position,
                                               const std::shared_ptr<KeyFrame>& reference,
                                               uint64_t first_keyframe_id) {
  MOSLAM_CHECK(points_.count(id) == 0) << "map point " << id << " restored twice";
  auto p = std::make_shared<MapPoint>(id, position, reference, first_keyframe_id);
  points_[id] = p;
  CountEntities();
  next_point_id_ = std::max(next_point_id_, id + 1);
  return p;
}

void Map::RestoreCounters(uint64_t next_keyframe_id, uint64_t next_point_id, uint64_t generation) {
  next_keyframe_id_ = std::max(next_keyframe_id_, next_keyframe_id);
  next_point_id_ = std::max(next_point_id_, next_point_id);
  generation_ = generation;
}

std::shared_ptr<KeyFrame> Map::keyframe(uint64_t id) const {
  auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second;
}

}  // namespace moslam::map
