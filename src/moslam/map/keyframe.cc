#include "moslam/map/keyframe.h"

#include <algorithm>
#include <utility>

#include "moslam/map/map_point.h"
#include "moslam/util/check.h"

namespace moslam::map {

namespace {
// ORB-SLAM2 keeps covisibility edges of at least 15 shared points.
constexpr int kMinEdgeWeight = 15;
}  // namespace

KeyFrame::KeyFrame(uint64_t id_in, feature::Frame frame_in, const geometry::SE3& T_cam_world)
    : id(id_in), frame(std::move(frame_in)) {
  points.assign(frame.size(), nullptr);
  SetPose(T_cam_world);
}

void KeyFrame::SetPose(const geometry::SE3& T_cam_world) {
  T_cam_world_ = T_cam_world;
  T_world_cam_ = T_cam_world.Inverse();
}

int KeyFrame::TrackedMapPoints(int min_observations) const {
  int n = 0;
  for (const auto& p : points) {
    if (p && !p->bad && p->num_observations() >= min_observations) ++n;
  }
  return n;
}

double KeyFrame::MedianDepth() const {
  std::vector<double> depths;
  for (const auto& p : points) {
    if (p && !p->bad) depths.push_back((T_cam_world_ * p->position).z());
  }
  if (depths.empty()) return 0.0;
  std::nth_element(depths.begin(), depths.begin() + depths.size() / 2, depths.end());
  return depths[depths.size() / 2];
}

void KeyFrame::UpdateConnections() {
  std::map<uint64_t, int> counter;
  std::map<uint64_t, std::shared_ptr<KeyFrame>> others;
  for (const auto& p : points) {
    if (!p || p->bad) continue;
    for (const auto& [kf_id, obs] : p->observations()) {
      if (kf_id == id) continue;
      auto kf = obs.keyframe.lock();
      if (!kf || kf->bad()) continue;
      ++counter[kf_id];
      others[kf_id] = kf;
    }
  }
  if (counter.empty()) return;
  uint64_t best_id = counter.begin()->first;
  int best = 0;
  for (const auto& [kf_id, w] : counter) {
    if (w > best) best = w, best_id = kf_id;
  }
  connected_.clear();
  weights_.clear();
  for (const auto& [kf_id, w] : counter) {
    if (w < kMinEdgeWeight && kf_id != best_id) continue;
    connected_[kf_id] = others[kf_id];
    weights_[kf_id] = w;
    others[kf_id]->AddConnection(shared_from_this(), w);
  }
  RebuildOrder();
  // The parent is the most covisible *earlier* keyframe, so the tree can never get a cycle even
  // when a newer keyframe already shares points (mapping lagging behind tracking).
  if (first_connection_ && id != 0) {
    std::shared_ptr<KeyFrame> parent;
    int parent_w = 0;
    for (const auto& [kf_id, w] : counter) {
      if (kf_id < id && w > parent_w) {
        parent_w = w;
        parent = others[kf_id];
      }
    }
    if (parent) {
      first_connection_ = false;
      SetParent(parent);
    }
  }
}

std::vector<std::shared_ptr<KeyFrame>> KeyFrame::BestCovisibles(int n) const {
  std::vector<std::shared_ptr<KeyFrame>> out;
  for (const auto& w : ordered_) {
    if (n >= 0 && static_cast<int>(out.size()) >= n) break;
    auto kf = w.lock();
    if (kf && !kf->bad()) out.push_back(kf);
  }
  return out;
}

int KeyFrame::Weight(uint64_t other_id) const {
  auto it = weights_.find(other_id);
  return it == weights_.end() ? 0 : it->second;
}

void KeyFrame::AddConnection(const std::shared_ptr<KeyFrame>& other, int weight) {
  connected_[other->id] = other;
  weights_[other->id] = weight;
  RebuildOrder();
}

void KeyFrame::EraseConnection(uint64_t other_id) {
  if (connected_.erase(other_id) == 0) return;
  weights_.erase(other_id);
  RebuildOrder();
}

void KeyFrame::SetParent(const std::shared_ptr<KeyFrame>& parent) {
  if (auto old = parent_.lock()) old->children_.erase(id);
  parent_ = parent;
  if (parent) parent->children_.insert(id);
}

void KeyFrame::RebuildOrder() {
  std::vector<std::pair<int, uint64_t>> order;
  for (const auto& [kf_id, w] : weights_) order.emplace_back(-w, kf_id);
  std::sort(order.begin(), order.end());
  ordered_.clear();
  for (const auto& [w, kf_id] : order) ordered_.push_back(connected_[kf_id]);
}

std::vector<std::shared_ptr<MapPoint>> KeyFrame::SetBad(
    const std::map<uint64_t, std::shared_ptr<KeyFrame>>& all_keyframes) {
  std::vector<std::shared_ptr<MapPoint>> orphaned;
  auto parent = parent_.lock();
  if (!parent || bad_) return orphaned;
  for (const auto& [kf_id, w] : connected_) {
    if (auto kf = w.lock()) kf->EraseConnection(id);
  }
  for (auto& p : points) {
    if (p && !p->bad && p->EraseObservation(id)) orphaned.push_back(p);
    p = nullptr;
  }
  connected_.clear();
  weights_.clear();
  ordered_.clear();
  // Reattach each child to its most covisible keyframe among the parent and the already
  // reattached ones (ORB-SLAM2's SetBadFlag, simplified to one candidate pass per child).
  std::set<uint64_t> candidates = {parent->id};
  for (uint64_t child_id : std::set<uint64_t>(children_)) {
    auto it = all_keyframes.find(child_id);
    if (it == all_keyframes.end() || it->second->bad()) continue;
    const auto& child = it->second;
    uint64_t best_id = parent->id;
    int best = -1;
    for (uint64_t c : candidates) {
      const int w = child->Weight(c);
      if (w > best) best = w, best_id = c;
    }
    auto new_parent = all_keyframes.at(best_id);
    child->SetParent(new_parent);
    candidates.insert(child_id);
  }
  children_.clear();
  parent->children_.erase(id);
  T_cam_parent_ = T_cam_world_ * parent->T_world_cam();
  bad_ = true;
  return orphaned;
}

}  // namespace moslam::map
