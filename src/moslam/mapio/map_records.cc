#include "moslam/mapio/map_records.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "moslam/map/keyframe.h"
#include "moslam/map/map_point.h"

namespace moslam::mapio::internal {
namespace {

constexpr uint64_t kNone = std::numeric_limits<uint64_t>::max();
constexpr int kDescriptorBytes = 32;

// Keypoints as two arrays (x, y, size, angle, response; octave, class_id): one copy each.
void WriteKeyPoints(const std::vector<cv::KeyPoint>& keypoints, Writer* out) {
  std::vector<float> f;
  std::vector<int32_t> i;
  f.reserve(keypoints.size() * 5);
  i.reserve(keypoints.size() * 2);
  for (const auto& k : keypoints) {
    f.insert(f.end(), {k.pt.x, k.pt.y, k.size, k.angle, k.response});
    i.insert(i.end(), {k.octave, k.class_id});
  }
  out->Vector(f);
  out->Vector(i);
}

std::vector<cv::KeyPoint> ReadKeyPoints(Reader* in, size_t n, int num_levels) {
  const auto f = in->Vector<float>();
  const auto i = in->Vector<int32_t>();
  if (f.size() != n * 5 || i.size() != n * 2) in->Fail("keypoint arrays of the wrong length");
  std::vector<cv::KeyPoint> keypoints(n);
  for (size_t k = 0; k < n; ++k) {
    keypoints[k] = cv::KeyPoint(f[5 * k], f[5 * k + 1], f[5 * k + 2], f[5 * k + 3], f[5 * k + 4],
                                i[2 * k], i[2 * k + 1]);
    if (i[2 * k] < 0 || i[2 * k] >= num_levels) in->Fail("a keypoint octave out of range");
    // Position, size, angle and response: the matchers bin angles and grid cells by casting
    // them to int, which a NaN or an infinity turns into undefined behaviour.
    if (!std::all_of(f.begin() + 5 * k, f.begin() + 5 * k + 5,
                     [](float v) { return std::isfinite(v); })) {
      in->Fail("a keypoint with a non-finite position, size, angle or response");
    }
  }
  return keypoints;
}

void WriteFrame(const feature::Frame& frame, Writer* out) {
  out->Value(frame.timestamp);
  out->Value(static_cast<uint64_t>(frame.size()));
  out->Vector(frame.scale_factors);
  out->Vector(frame.inv_scale_factors);
  out->Vector(frame.level_sigma2);
  out->Vector(frame.inv_level_sigma2);
  WriteKeyPoints(frame.keypoints, out);
  WriteKeyPoints(frame.keypoints_undistorted, out);
  std::vector<uint8_t> descriptors(frame.size() * kDescriptorBytes);
  for (size_t k = 0; k < frame.size(); ++k) {
    std::copy(frame.descriptor(k), frame.descriptor(k) + kDescriptorBytes,
              descriptors.begin() + static_cast<std::ptrdiff_t>(k * kDescriptorBytes));
  }
  out->Vector(descriptors);
  out->Vector(frame.u_right);
  out->Vector(frame.depth);
  out->Vector(frame.near_movable);
  out->Vector(frame.moving);
  out->Value(frame.bf);
  for (float b : {frame.bounds.min_x, frame.bounds.max_x, frame.bounds.min_y, frame.bounds.max_y})
    out->Value(b);
}

feature::Frame ReadFrame(Reader* in) {
  feature::Frame frame;
  frame.timestamp = in->Value<double>();
  const auto n = in->Value<uint64_t>();
  // Each keypoint takes more than 32 bytes below: a larger count cannot be right.
  if (n > in->left() / kDescriptorBytes) in->Fail("a keypoint count larger than the file");
  frame.scale_factors = in->Vector<float>();
  frame.inv_scale_factors = in->Vector<float>();
  frame.level_sigma2 = in->Vector<float>();
  frame.inv_level_sigma2 = in->Vector<float>();
  const size_t levels = frame.scale_factors.size();
  if (levels == 0 || frame.inv_scale_factors.size() != levels ||
      frame.level_sigma2.size() != levels || frame.inv_level_sigma2.size() != levels) {
    in->Fail("scale pyramid arrays empty or of different lengths");
  }
  for (const auto* pyramid : {&frame.scale_factors, &frame.inv_scale_factors, &frame.level_sigma2,
                              &frame.inv_level_sigma2}) {
    if (!std::all_of(pyramid->begin(), pyramid->end(),
                     [](float v) { return std::isfinite(v) && v > 0.0f; })) {
      in->Fail("a scale pyramid value that is not a positive finite number");
    }
  }
  frame.keypoints = ReadKeyPoints(in, n, static_cast<int>(levels));
  frame.keypoints_undistorted = ReadKeyPoints(in, n, static_cast<int>(levels));
  const auto descriptors = in->Vector<uint8_t>();
  if (descriptors.size() != n * kDescriptorBytes) in->Fail("descriptors of the wrong length");
  frame.descriptors = cv::Mat(static_cast<int>(n), kDescriptorBytes, CV_8U);
  if (n > 0) std::copy(descriptors.begin(), descriptors.end(), frame.descriptors.ptr<uint8_t>());
  frame.u_right = in->Vector<float>();
  frame.depth = in->Vector<float>();
  frame.near_movable = in->Vector<uint8_t>();
  frame.moving = in->Vector<uint8_t>();
  if (frame.u_right.size() != n || frame.depth.size() != n ||
      (!frame.near_movable.empty() && frame.near_movable.size() != n) ||
      (!frame.moving.empty() && frame.moving.size() != n)) {
    in->Fail("per-keypoint arrays of the wrong length");
  }
  // Depth and right coordinate: a measured value or negative for none; never NaN or infinite.
  const auto finite = [](float v) { return std::isfinite(v); };
  if (!std::all_of(frame.u_right.begin(), frame.u_right.end(), finite) ||
      !std::all_of(frame.depth.begin(), frame.depth.end(), finite)) {
    in->Fail("a non-finite keypoint depth or right coordinate");
  }
  frame.bf = in->Value<double>();
  frame.bounds.min_x = in->Value<float>();
  frame.bounds.max_x = in->Value<float>();
  frame.bounds.min_y = in->Value<float>();
  frame.bounds.max_y = in->Value<float>();
  if (!std::isfinite(frame.timestamp) || !std::isfinite(frame.bf)) {
    in->Fail("a non-finite timestamp or stereo baseline");
  }
  // The grid is not stored: it is a function of the bounds and the keypoints. Infinite bounds
  // (a fuzzer's finding) made its cell of a keypoint NaN, cast to int.
  const feature::ImageBounds& b = frame.bounds;
  if (!(std::isfinite(b.min_x) && std::isfinite(b.max_x) && std::isfinite(b.min_y) &&
        std::isfinite(b.max_y) && b.max_x > b.min_x && b.max_y > b.min_y)) {
    in->Fail("empty or non-finite image bounds");
  }
  frame.grid = feature::KeypointGrid(frame.bounds, frame.keypoints_undistorted);
  return frame;
}

void WriteBow(const map::KeyFrame& kf, Writer* out) {
  std::vector<uint32_t> words, nodes, counts, indices;
  std::vector<double> weights;
  for (const auto& [word, weight] : kf.bow) words.push_back(word), weights.push_back(weight);
  for (const auto& [node, features] : kf.bow_features) {
    nodes.push_back(node);
    counts.push_back(static_cast<uint32_t>(features.size()));
    indices.insert(indices.end(), features.begin(), features.end());
  }
  out->Vector(words);
  out->Vector(weights);
  out->Vector(nodes);
  out->Vector(counts);
  out->Vector(indices);
}

void ReadBow(Reader* in, map::KeyFrame* kf) {
  const auto words = in->Vector<uint32_t>();
  const auto weights = in->Vector<double>();
  const auto nodes = in->Vector<uint32_t>();
  const auto counts = in->Vector<uint32_t>();
  const auto indices = in->Vector<uint32_t>();
  if (words.size() != weights.size() || nodes.size() != counts.size()) {
    in->Fail("bag-of-words arrays of different lengths");
  }
  for (size_t k = 0; k < words.size(); ++k) {
    // Strictly increasing, as the map wrote them: otherwise a second save would reorder them.
    if (k > 0 && words[k] <= words[k - 1]) in->Fail("bag-of-words words not in order");
    kf->bow.emplace_hint(kf->bow.end(), words[k], weights[k]);
  }
  size_t next = 0;
  for (size_t k = 0; k < nodes.size(); ++k) {
    if (k > 0 && nodes[k] <= nodes[k - 1]) in->Fail("direct-index nodes not in order");
    if (counts[k] > indices.size() - next) in->Fail("direct-index counts beyond its indices");
    std::vector<uint32_t> features(indices.begin() + static_cast<std::ptrdiff_t>(next),
                                   indices.begin() + static_cast<std::ptrdiff_t>(next + counts[k]));
    for (uint32_t f : features) {
      if (f >= kf->frame.size()) in->Fail("a direct-index feature out of range");
    }
    next += counts[k];
    kf->bow_features.emplace_hint(kf->bow_features.end(), nodes[k], std::move(features));
  }
  if (next != indices.size()) in->Fail("direct-index indices left over");
}

geometry::SE3 ReadPose(Reader* in) {
  double c[7];
  for (double& v : c) v = in->Value<double>();
  const Eigen::Quaterniond q(c[3], c[0], c[1], c[2]);  // stored x, y, z, w (Eigen's coeffs)
  for (double v : c) {
    if (!std::isfinite(v)) in->Fail("a non-finite pose");
  }
  if (std::abs(q.norm() - 1.0) > 1e-6) in->Fail("a pose rotation that is not a unit quaternion");
  return geometry::SE3(q, Eigen::Vector3d(c[4], c[5], c[6]));
}

std::shared_ptr<map::KeyFrame> KeyFrameOf(Reader* in, const map::Map& map, uint64_t id,
                                          const char* what) {
  auto kf = map.keyframe(id);
  if (!kf)
    in->Fail(std::string(what) + " refers to keyframe " + std::to_string(id) + ", not in the map");
  return kf;
}

}  // namespace

void WriteKeyFrame(const map::KeyFrame& kf, Writer* out) {
  out->Value(kf.id);
  const geometry::SE3& T = kf.T_cam_world();
  for (int k = 0; k < 4; ++k) out->Value(T.rotation().coeffs()[k]);
  for (int k = 0; k < 3; ++k) out->Value(T.translation()[k]);
  WriteFrame(kf.frame, out);
  WriteBow(kf, out);
}

std::shared_ptr<map::KeyFrame> ReadKeyFrame(Reader* in, map::Map* map) {
  const auto id = in->Value<uint64_t>();
  in->SetRecord("keyframe " + std::to_string(id));
  if (!map->keyframes().empty() && id <= map->keyframes().rbegin()->first) {
    in->Fail("keyframe ids not increasing");
  }
  const geometry::SE3 T_cam_world = ReadPose(in);
  auto kf = map->RestoreKeyFrame(id, ReadFrame(in), T_cam_world);
  ReadBow(in, kf.get());
  return kf;
}

void WritePoint(const map::MapPoint& p, const map::Map& map, Writer* out) {
  out->Value(p.id);
  for (int k = 0; k < 3; ++k) out->Value(p.position[k]);
  for (int k = 0; k < 3; ++k) out->Value(p.normal[k]);
  out->Value(p.min_distance);
  out->Value(p.max_distance);
  std::vector<uint8_t> descriptor;
  if (!p.descriptor.empty())
    descriptor.assign(p.descriptor.ptr<uint8_t>(), p.descriptor.ptr<uint8_t>() + kDescriptorBytes);
  out->Vector(descriptor);
  std::vector<uint64_t> kf_ids;
  std::vector<uint32_t> indices;
  for (const auto& [kf_id, obs] : p.observations()) {
    if (!map.keyframe(kf_id)) continue;
    kf_ids.push_back(kf_id);
    indices.push_back(static_cast<uint32_t>(obs.index));
  }
  uint64_t reference = kNone;
  if (auto ref = p.reference.lock(); ref && map.keyframe(ref->id)) {
    reference = ref->id;
  } else if (!kf_ids.empty()) {
    reference = kf_ids.front();
  }
  out->Value(reference);
  out->Value(p.first_keyframe_id);
  for (int v : {p.visible, p.found, p.movable_evidence, p.free_space_evidence}) {
    out->Value(static_cast<int32_t>(v));
  }
  out->Vector(kf_ids);
  out->Vector(indices);
}

void ReadPoint(Reader* in, map::Map* map) {
  const auto id = in->Value<uint64_t>();
  in->SetRecord("map point " + std::to_string(id));
  if (!map->points().empty() && id <= map->points().rbegin()->first) {
    in->Fail("map point ids not increasing");
  }
  double c[6];
  for (double& v : c) {
    v = in->Value<double>();
    if (!std::isfinite(v)) in->Fail("a non-finite position or normal");
  }
  const float min_distance = in->Value<float>();
  const float max_distance = in->Value<float>();
  // The scale prediction takes a logarithm of their ratio to a distance and casts it to a level.
  if (!(std::isfinite(min_distance) && std::isfinite(max_distance) && min_distance >= 0.0f &&
        min_distance <= max_distance)) {
    in->Fail("a scale-invariance range that is not 0 <= min <= max, finite");
  }
  const auto descriptor = in->Vector<uint8_t>();
  if (!descriptor.empty() && descriptor.size() != kDescriptorBytes)
    in->Fail("a descriptor not of 32 bytes");
  const auto reference_id = in->Value<uint64_t>();
  const auto first_keyframe_id = in->Value<uint64_t>();
  std::shared_ptr<map::KeyFrame> reference;
  if (reference_id != kNone) reference = KeyFrameOf(in, *map, reference_id, "its reference");
  auto p =
      map->RestoreMapPoint(id, Eigen::Vector3d(c[0], c[1], c[2]), reference, first_keyframe_id);
  p->normal = Eigen::Vector3d(c[3], c[4], c[5]);
  p->min_distance = min_distance;
  p->max_distance = max_distance;
  if (!descriptor.empty()) {
    p->descriptor = cv::Mat(1, kDescriptorBytes, CV_8U);
    std::copy(descriptor.begin(), descriptor.end(), p->descriptor.ptr<uint8_t>());
  }
  p->visible = in->Value<int32_t>();
  p->found = in->Value<int32_t>();
  p->movable_evidence = in->Value<int32_t>();
  p->free_space_evidence = in->Value<int32_t>();
  if (p->visible <= 0) in->Fail("a point never visible");  // FoundRatio divides by it
  const auto kf_ids = in->Vector<uint64_t>();
  const auto indices = in->Vector<uint32_t>();
  if (kf_ids.size() != indices.size()) in->Fail("observation arrays of different lengths");
  for (size_t k = 0; k < kf_ids.size(); ++k) {
    if (k > 0 && kf_ids[k] <= kf_ids[k - 1]) in->Fail("observations not in keyframe order");
    auto kf = KeyFrameOf(in, *map, kf_ids[k], "an observation");
    if (indices[k] >= kf->frame.size()) in->Fail("an observation's keypoint index out of range");
    p->AddObservation(kf, indices[k]);
  }
}

void WriteGraph(const map::KeyFrame& kf, const map::Map& map, Writer* out) {
  out->Value(kf.id);
  std::vector<uint32_t> indices;
  std::vector<uint64_t> point_ids;
  for (size_t k = 0; k < kf.points.size(); ++k) {
    const auto& p = kf.points[k];
    if (!p || map.points().count(p->id) == 0) continue;
    indices.push_back(static_cast<uint32_t>(k));
    point_ids.push_back(p->id);
  }
  out->Vector(indices);
  out->Vector(point_ids);
  std::vector<uint64_t> connected;
  std::vector<int32_t> weights;
  for (const auto& [other, w] : kf.connection_weights()) {
    if (!map.keyframe(other)) continue;
    connected.push_back(other);
    weights.push_back(w);
  }
  out->Vector(connected);
  out->Vector(weights);
  auto parent = kf.parent();
  out->Value(parent && map.keyframe(parent->id) ? parent->id : kNone);
  out->Value(static_cast<uint8_t>(kf.first_connection() ? 1 : 0));
}

void ReadGraph(Reader* in, map::Map* map) {
  const auto id = in->Value<uint64_t>();
  in->SetRecord("graph of keyframe " + std::to_string(id));
  auto kf = KeyFrameOf(in, *map, id, "the graph record");
  const auto indices = in->Vector<uint32_t>();
  const auto point_ids = in->Vector<uint64_t>();
  if (indices.size() != point_ids.size()) in->Fail("keypoint-to-point arrays of different lengths");
  for (size_t k = 0; k < indices.size(); ++k) {
    auto it = map->points().find(point_ids[k]);
    if (it == map->points().end()) in->Fail("a keypoint's map point not in the map");
    if (indices[k] >= kf->points.size()) in->Fail("a keypoint index out of range");
    kf->points[indices[k]] = it->second;
  }
  const auto connected = in->Vector<uint64_t>();
  const auto weights = in->Vector<int32_t>();
  if (connected.size() != weights.size()) in->Fail("covisibility arrays of different lengths");
  for (size_t k = 0; k < connected.size(); ++k) {
    if (connected[k] == id) in->Fail("a covisibility edge to itself");
    kf->AddConnection(KeyFrameOf(in, *map, connected[k], "a covisibility edge"), weights[k]);
  }
  const auto parent_id = in->Value<uint64_t>();
  if (parent_id != kNone) {
    if (parent_id == id) in->Fail("a keyframe its own parent");
    kf->SetParent(KeyFrameOf(in, *map, parent_id, "the spanning-tree parent"));
  }
  const auto first = in->Value<uint8_t>();
  if (first > 1) in->Fail("a flag neither 0 nor 1");
  kf->RestoreFirstConnection(first == 1);
}

}  // namespace moslam::mapio::internal
