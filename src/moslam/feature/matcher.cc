#include "moslam/feature/matcher.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::feature {
namespace {

int RotationBin(float angle_difference) {
  float rot = std::fmod(angle_difference, 360.0f);
  if (rot < 0.0f) rot += 360.0f;
  // ORB-SLAM2 writes factor = 1 / HISTO_LENGTH, which puts nearly everything in bin 0 for angles
  // in degrees; 30 / 360 gives the intended 12-degree bins.
  int bin = static_cast<int>(std::lround(rot * kRotationBins / 360.0f));
  if (bin == kRotationBins) bin = 0;
  return bin;
}

void CheckDistance(int distance, const char* name) {
  if (distance < 0 || distance > 256) ThrowInput("{} must be in [0, 256] (got {})", name, distance);
}

}  // namespace

void DescriptorMatchOptions::Check() const {
  CheckDistance(max_distance, "descriptor match max_distance");
  if (!(ratio > 0.0f && ratio <= 1.0f)) ThrowInput("descriptor match ratio must be in (0, 1]");
}

void ProjectionMatchOptions::Check() const {
  CheckDistance(max_distance, "projection match max_distance");
  if (!(ratio > 0.0f && ratio <= 1.0f)) ThrowInput("projection match ratio must be in (0, 1]");
  if (!(radius > 0.0f)) ThrowInput("projection match radius must be > 0");
}

std::vector<bool> RotationConsistent(const std::vector<float>& angle_differences) {
  std::array<int, kRotationBins> counts{};
  std::vector<int> bins(angle_differences.size());
  for (size_t i = 0; i < angle_differences.size(); ++i) {
    bins[i] = RotationBin(angle_differences[i]);
    ++counts[bins[i]];
  }
  // The three largest bins; the second and third only when they hold >= 10% of the first.
  std::array<int, kRotationBins> order;
  for (int b = 0; b < kRotationBins; ++b) order[b] = b;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return counts[a] > counts[b]; });
  std::array<bool, kRotationBins> keep{};
  keep[order[0]] = counts[order[0]] > 0;
  const float min_count = 0.1f * static_cast<float>(counts[order[0]]);
  if (counts[order[1]] >= min_count && counts[order[1]] > 0) {
    keep[order[1]] = true;
    if (counts[order[2]] >= min_count && counts[order[2]] > 0) keep[order[2]] = true;
  }
  std::vector<bool> result(angle_differences.size());
  for (size_t i = 0; i < bins.size(); ++i) result[i] = keep[bins[i]];
  return result;
}

std::vector<DescriptorMatch> MatchByDescriptor(const std::vector<cv::KeyPoint>& keypoints1,
                                               const cv::Mat& descriptors1,
                                               const std::vector<cv::KeyPoint>& keypoints2,
                                               const cv::Mat& descriptors2,
                                               const DescriptorMatchOptions& options) {
  options.Check();
  const int n1 = static_cast<int>(keypoints1.size());
  const int n2 = static_cast<int>(keypoints2.size());
  MOSLAM_CHECK(descriptors1.rows == n1 && descriptors2.rows == n2);
  // by_index2[j]: the best candidate so far that chose keypoint j of the second set.
  std::vector<DescriptorMatch> by_index2(n2);
  for (int i = 0; i < n1; ++i) {
    const uint8_t* d1 = descriptors1.ptr<uint8_t>(i);
    int best = 257, second = 257, best_j = -1;
    for (int j = 0; j < n2; ++j) {
      const int dist = DescriptorDistance(d1, descriptors2.ptr<uint8_t>(j));
      if (dist < best) {
        second = best;
        best = dist;
        best_j = j;
      } else if (dist < second) {
        second = dist;
      }
    }
    if (best_j < 0 || best > options.max_distance) continue;
    if (static_cast<float>(best) >= options.ratio * static_cast<float>(second)) continue;
    DescriptorMatch& slot = by_index2[best_j];
    if (slot.index1 < 0 || best < slot.distance) slot = DescriptorMatch{i, best_j, best};
  }
  std::vector<DescriptorMatch> matches;
  for (const DescriptorMatch& m : by_index2) {
    if (m.index1 >= 0) matches.push_back(m);
  }
  std::sort(matches.begin(), matches.end(),
            [](const DescriptorMatch& a, const DescriptorMatch& b) { return a.index1 < b.index1; });
  if (!options.check_orientation) return matches;
  std::vector<float> angles(matches.size());
  for (size_t k = 0; k < matches.size(); ++k) {
    angles[k] = keypoints1[matches[k].index1].angle - keypoints2[matches[k].index2].angle;
  }
  const std::vector<bool> keep = RotationConsistent(angles);
  std::vector<DescriptorMatch> consistent;
  for (size_t k = 0; k < matches.size(); ++k) {
    if (keep[k]) consistent.push_back(matches[k]);
  }
  return consistent;
}

std::vector<int> MatchByProjection(const Frame& frame, const std::vector<ProjectedPoint>& points,
                                   const ProjectionMatchOptions& options) {
  options.Check();
  std::vector<int> result(points.size(), -1);
  // claim[k]: (distance, point) currently holding frame keypoint k.
  std::vector<std::pair<int, int>> claim(frame.size(), {std::numeric_limits<int>::max(), -1});
  const int levels = frame.num_levels();
  for (size_t p = 0; p < points.size(); ++p) {
    const ProjectedPoint& point = points[p];
    MOSLAM_CHECK(point.descriptor != nullptr);
    if (point.octave < 0 || point.octave >= levels) continue;
    const float r = options.radius * frame.scale_factors[point.octave];
    const std::vector<size_t> candidates =
        frame.FeaturesInArea(point.pixel.x(), point.pixel.y(), r, point.octave - 1, point.octave);
    int best = 257, second = 257, best_level = -1, second_level = -1, best_k = -1;
    for (const size_t k : candidates) {
      if (point.u_right >= 0.0f && frame.u_right[k] > 0.0f &&
          std::abs(point.u_right - frame.u_right[k]) > r) {
        continue;
      }
      const int dist = DescriptorDistance(point.descriptor, frame.descriptor(k));
      const int level = frame.keypoints_undistorted[k].octave;
      if (dist < best) {
        second = best;
        second_level = best_level;
        best = dist;
        best_level = level;
        best_k = static_cast<int>(k);
      } else if (dist < second) {
        second = dist;
        second_level = level;
      }
    }
    if (best_k < 0 || best > options.max_distance) continue;
    if (best_level == second_level &&
        static_cast<float>(best) > options.ratio * static_cast<float>(second)) {
      continue;
    }
    auto& holder = claim[best_k];
    if (best >= holder.first) continue;
    if (holder.second >= 0) result[holder.second] = -1;
    holder = {best, static_cast<int>(p)};
    result[p] = best_k;
  }
  return result;
}

}  // namespace moslam::feature
