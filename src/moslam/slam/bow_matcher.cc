#include "moslam/slam/bow_matcher.h"

#include <algorithm>
#include <limits>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/util/error.h"

namespace moslam::slam {

void BowMatchOptions::Check() const {
  if (max_distance < 0 || max_distance > 256) {
    throw InputError("BowMatchOptions.max_distance must be in [0, 256]");
  }
  if (!(ratio > 0.0f && ratio <= 1.0f)) throw InputError("BowMatchOptions.ratio must be in (0, 1]");
}

namespace {

struct Best {
  int distance = 256;
  int second = 256;
  int index = -1;
  void Offer(int d, int i) {
    if (d < distance) {
      second = distance;
      distance = d;
      index = i;
    } else if (d < second) {
      second = d;
    }
  }
};

// Calls visit(indices1, indices2) for every node the two direct indexes share (one merge pass
// over the node-ordered maps, as ORB-SLAM2's lower_bound walk).
template <typename Visit>
void ForSharedNodes(const vocab::FeatureVector& a, const vocab::FeatureVector& b, Visit visit) {
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first == ib->first) {
      visit(ia->second, ib->second);
      ++ia;
      ++ib;
    } else if (ia->first < ib->first) {
      ia = a.lower_bound(ib->first);
    } else {
      ib = b.lower_bound(ia->first);
    }
  }
}

// Drops matches outside the dominant keypoint-rotation bins. `matched[k]` indexes `result`.
void FilterOrientation(const std::vector<float>& angle_differences,
                       const std::vector<size_t>& matched,
                       std::vector<std::shared_ptr<map::MapPoint>>* result) {
  const std::vector<bool> keep = feature::RotationConsistent(angle_differences);
  for (size_t k = 0; k < matched.size(); ++k) {
    if (!keep[k]) (*result)[matched[k]] = nullptr;
  }
}

}  // namespace

std::vector<std::shared_ptr<map::MapPoint>> SearchByBoW(const map::KeyFrame& keyframe,
                                                        const feature::Frame& frame,
                                                        const vocab::FeatureVector& frame_features,
                                                        const BowMatchOptions& options) {
  options.Check();
  std::vector<std::shared_ptr<map::MapPoint>> result(frame.size());
  std::vector<float> angles;
  std::vector<size_t> matched;
  const auto& kf_keys = keyframe.frame.keypoints_undistorted;
  ForSharedNodes(
      keyframe.bow_features, frame_features,
      [&](const std::vector<uint32_t>& kf_idx, const std::vector<uint32_t>& f_idx) {
        for (uint32_t i : kf_idx) {
          const auto& point = keyframe.points[i];
          if (!point || point->bad) continue;
          const uint8_t* d_kf = keyframe.frame.descriptor(i);
          Best best;
          for (uint32_t j : f_idx) {
            if (result[j]) continue;  // taken by an earlier keyframe feature (ORB-SLAM2)
            best.Offer(feature::DescriptorDistance(d_kf, frame.descriptor(j)), static_cast<int>(j));
          }
          if (best.index < 0 || best.distance > options.max_distance) continue;
          if (!(best.distance < options.ratio * best.second)) continue;
          result[best.index] = point;
          angles.push_back(kf_keys[i].angle - frame.keypoints_undistorted[best.index].angle);
          matched.push_back(static_cast<size_t>(best.index));
        }
      });
  if (options.check_orientation) FilterOrientation(angles, matched, &result);
  return result;
}

std::vector<std::shared_ptr<map::MapPoint>> SearchByBoW(const map::KeyFrame& keyframe1,
                                                        const map::KeyFrame& keyframe2,
                                                        const BowMatchOptions& options) {
  options.Check();
  std::vector<std::shared_ptr<map::MapPoint>> result(keyframe1.points.size());
  std::vector<bool> taken2(keyframe2.points.size(), false);
  std::vector<float> angles;
  std::vector<size_t> matched;
  ForSharedNodes(keyframe1.bow_features, keyframe2.bow_features,
                 [&](const std::vector<uint32_t>& idx1, const std::vector<uint32_t>& idx2) {
                   for (uint32_t i : idx1) {
                     const auto& p1 = keyframe1.points[i];
                     if (!p1 || p1->bad) continue;
                     const uint8_t* d1 = keyframe1.frame.descriptor(i);
                     Best best;
                     for (uint32_t j : idx2) {
                       const auto& p2 = keyframe2.points[j];
                       if (taken2[j] || !p2 || p2->bad) continue;
                       best.Offer(feature::DescriptorDistance(d1, keyframe2.frame.descriptor(j)),
                                  static_cast<int>(j));
                     }
                     // ORB-SLAM2 accepts strictly below TH_LOW here (<= in the frame version).
                     if (best.index < 0 || best.distance >= options.max_distance) continue;
                     if (!(best.distance < options.ratio * best.second)) continue;
                     result[i] = keyframe2.points[best.index];
                     taken2[best.index] = true;
                     angles.push_back(keyframe1.frame.keypoints_undistorted[i].angle -
                                      keyframe2.frame.keypoints_undistorted[best.index].angle);
                     matched.push_back(i);
                   }
                 });
  if (options.check_orientation) FilterOrientation(angles, matched, &result);
  return result;
}

int CountMatches(const std::vector<std::shared_ptr<map::MapPoint>>& matches) {
  return static_cast<int>(
      std::count_if(matches.begin(), matches.end(), [](const auto& p) { return p != nullptr; }));
}

}  // namespace moslam::slam
