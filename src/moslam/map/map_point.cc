#include "moslam/map/map_point.h"

#include <algorithm>
#include <climits>
#include <cmath>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/map/keyframe.h"

namespace moslam::map {

MapPoint::MapPoint(uint64_t id_in, const Eigen::Vector3d& position_in,
                   const std::shared_ptr<KeyFrame>& ref, uint64_t first_keyframe_id_in)
    : id(id_in), position(position_in), reference(ref), first_keyframe_id(first_keyframe_id_in) {}

int MapPoint::IndexIn(uint64_t keyframe_id) const {
  auto it = observations_.find(keyframe_id);
  return it == observations_.end() ? -1 : static_cast<int>(it->second.index);
}

void MapPoint::AddObservation(const std::shared_ptr<KeyFrame>& keyframe, size_t index) {
  if (observations_.count(keyframe->id)) return;
  observations_[keyframe->id] = Observation{keyframe, index};
  num_obs_ += keyframe->frame.u_right[index] >= 0.0f ? 2 : 1;
}

bool MapPoint::EraseObservation(uint64_t keyframe_id) {
  auto it = observations_.find(keyframe_id);
  if (it == observations_.end()) return false;
  auto kf = it->second.keyframe.lock();
  const bool stereo = kf && kf->frame.u_right[it->second.index] >= 0.0f;
  num_obs_ -= stereo ? 2 : 1;
  observations_.erase(it);
  auto ref = reference.lock();
  if ((!ref || ref->id == keyframe_id) && !observations_.empty()) {
    reference = observations_.begin()->second.keyframe;
  }
  return num_obs_ <= 2;
}

void MapPoint::ComputeDistinctiveDescriptor() {
  std::vector<const uint8_t*> descs;
  for (const auto& [kf_id, obs] : observations_) {
    auto kf = obs.keyframe.lock();
    if (kf && !kf->bad()) descs.push_back(kf->frame.descriptor(obs.index));
  }
  if (descs.empty()) return;
  const size_t n = descs.size();
  size_t best_index = 0;
  int best_median = INT_MAX;
  std::vector<int> row(n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t j = 0; j < n; ++j) row[j] = feature::DescriptorDistance(descs[i], descs[j]);
    std::nth_element(row.begin(), row.begin() + (n - 1) / 2, row.end());
    const int median = row[(n - 1) / 2];
    if (median < best_median) best_median = median, best_index = i;
  }
  descriptor = cv::Mat(1, 32, CV_8U);
  std::copy(descs[best_index], descs[best_index] + 32, descriptor.ptr<uint8_t>());
}

void MapPoint::UpdateNormalAndDepth() {
  auto ref = reference.lock();
  if (observations_.empty() || !ref) return;
  Eigen::Vector3d normal_sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& [kf_id, obs] : observations_) {
    auto kf = obs.keyframe.lock();
    if (!kf) continue;
    normal_sum += (position - kf->CameraCenter()).normalized();
    ++n;
  }
  if (n == 0) return;
  normal = normal_sum / n;
  const int ref_index = IndexIn(ref->id);
  if (ref_index < 0) return;
  const float dist = static_cast<float>((position - ref->CameraCenter()).norm());
  const int level = ref->frame.keypoints_undistorted[ref_index].octave;
  const float level_factor = ref->frame.scale_factors[level];
  const int num_levels = ref->frame.num_levels();
  max_distance = dist * level_factor;
  min_distance = max_distance / ref->frame.scale_factors[num_levels - 1];
}

int MapPoint::PredictScale(float distance, float log_scale_factor, int num_levels) const {
  const float ratio = max_distance / distance;
  int level = static_cast<int>(std::ceil(std::log(ratio) / log_scale_factor));
  return std::clamp(level, 0, num_levels - 1);
}

}  // namespace moslam::map
