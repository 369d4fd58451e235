// Test and benchmark support: a map shaped like a real run's (keyframes along a path, each with
// its own features and bag of words, points seen by a few consecutive keyframes, covisibility
// graph and spanning tree from UpdateConnections, a loop edge, an erased keyframe and point), from
// a seed, without running the system.
#pragma once

#include <algorithm>
#include <cstdint>
#include <memory>
#include <random>
#include <vector>

#include "moslam/map/map.h"

namespace moslam::mapio::testing {

inline feature::Frame RandomFrame(int n, double timestamp, std::mt19937* rng) {
  std::uniform_real_distribution<float> u(0.0f, 640.0f), v(0.0f, 480.0f), d(0.5f, 8.0f);
  std::uniform_int_distribution<int> octave(0, 7), byte(0, 255), coin(0, 3);
  feature::Frame f;
  f.timestamp = timestamp;
  for (int l = 0; l < 8; ++l) {
    const float s = std::pow(1.2f, static_cast<float>(l));
    f.scale_factors.push_back(s);
    f.inv_scale_factors.push_back(1.0f / s);
    f.level_sigma2.push_back(s * s);
    f.inv_level_sigma2.push_back(1.0f / (s * s));
  }
  f.descriptors = cv::Mat(n, 32, CV_8U);
  for (int i = 0; i < n; ++i) {
    cv::KeyPoint k(u(*rng), v(*rng), 31.0f, u(*rng) / 2.0f, d(*rng), octave(*rng));
    f.keypoints.push_back(k);
    k.pt.x += 0.25f;  // undistorted: a little elsewhere, so a swap of the two would show
    f.keypoints_undistorted.push_back(k);
    for (int b = 0; b < 32; ++b) f.descriptors.at<uint8_t>(i, b) = static_cast<uint8_t>(byte(*rng));
    const bool has_depth = coin(*rng) != 0;
    const float depth = d(*rng);
    f.depth.push_back(has_depth ? depth : -1.0f);
    f.u_right.push_back(has_depth ? k.pt.x - 40.0f / depth : -1.0f);
    f.near_movable.push_back(coin(*rng) == 0 ? 1 : 0);
  }
  f.bf = 40.0;
  f.bounds = {0.0f, 640.0f, 0.0f, 480.0f};
  f.grid = feature::KeypointGrid(f.bounds, f.keypoints_undistorted);
  return f;
}

// `keyframes` keyframes of `features` keypoints; a third of each keyframe's keypoints seed points
// seen by it and its next two keyframes. `edit_frame` (optional) changes each keyframe's frame
// before it enters the map (tests of values a writer never produces).
inline void BuildTestMap(int keyframes, int features, uint32_t seed, map::Map* map,
                         const std::function<void(feature::Frame*)>& edit_frame = {}) {
  std::mt19937 rng(seed);
  std::lock_guard<std::mutex> lock(map->mutex());
  std::vector<std::shared_ptr<map::KeyFrame>> kfs;
  for (int k = 0; k < keyframes; ++k) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(0.01 * k, Eigen::Vector3d::UnitY()));
    feature::Frame frame = RandomFrame(features, 0.1 * k, &rng);
    if (edit_frame) edit_frame(&frame);
    auto kf = map->CreateKeyFrame(std::move(frame),
                                  geometry::SE3(q, Eigen::Vector3d(-0.1 * k, 0.0, 0.0)));
    std::uniform_int_distribution<uint32_t> word(0, 9999), node(0, 99);
    for (int w = 0; w < 300; ++w) kf->bow[word(rng)] = 1.0 / 300.0;
    for (int i = 0; i < features; ++i) kf->bow_features[node(rng)].push_back(i);
    kfs.push_back(kf);
  }
  // Points: keypoint i of keyframe k (i % 3 == 0) with the same keypoint of the next two.
  for (int k = 0; k < keyframes; ++k) {
    for (int i = 0; i < features; i += 3) {
      if (kfs[k]->points[i]) continue;
      auto p = map->CreateMapPoint(Eigen::Vector3d(0.1 * k, 0.01 * i, 4.0), kfs[k]);
      for (int j = k; j < std::min(keyframes, k + 3); ++j) {
        kfs[j]->points[i] = p;
        p->AddObservation(kfs[j], i);
      }
      p->ComputeDistinctiveDescriptor();
      p->UpdateNormalAndDepth();
      p->visible = 3 + i % 5;
      p->found = 2 + i % 3;
    }
  }
  for (const auto& kf : kfs) kf->UpdateConnections();
  if (keyframes > 2) map->AddLoopEdge(kfs.front()->id, kfs.back()->id);
  // Erased entities must not reach the file (nor dangling references to them).
  if (keyframes > 4) map->EraseKeyFrame(kfs[2]);
  if (!map->points().empty()) map->EraseMapPoint(map->points().begin()->second);
}

}  // namespace moslam::mapio::testing
