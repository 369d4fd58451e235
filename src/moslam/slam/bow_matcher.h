// Descriptor matching through the bag-of-words direct index (ORB-SLAM2's ORBmatcher::SearchByBoW,
// Mur-Artal & Tardós 2017; the direct index of DBoW2, Gálvez-López & Tardós 2012): only features
// that fall under the same vocabulary node at the direct-index level are compared, which makes
// matching a keyframe against a frame (relocalization) or another keyframe (loop closing) a
// fraction of a brute-force search, and no worse where it matters (true matches share a node).
//
// Callers hold Map::mutex() (the keyframes' points are read). The keyframes' bow_features and the
// frame's FeatureVector must come from the same vocabulary and direct-index level
// (KeyFrameDatabase::ComputeBow).
#pragma once

#include <memory>
#include <vector>

#include "moslam/feature/frame.h"
#include "moslam/feature/matcher.h"
#include "moslam/map/keyframe.h"
#include "moslam/map/map_point.h"
#include "moslam/vocab/bow.h"

namespace moslam::slam {

struct BowMatchOptions {
  int max_distance = feature::kThLow;  // Hamming distance of an accepted best match (TH_LOW, 50)
  // Best < ratio * second best. ORB-SLAM2: 0.75 in relocalization (ORBmatcher(0.75, true)) and in
  // loop detection; tracking the reference keyframe uses 0.7.
  float ratio = 0.75f;
  // Keep only matches in the three dominant bins of the keypoint-angle-difference histogram
  // (feature::RotationConsistent).
  bool check_orientation = true;
  void Check() const;  // InputError naming the field
};

// Matches the keyframe's map points to the frame's keypoints. `frame_features` is the frame's
// direct index. Returns, per keypoint of `frame`, the keyframe's map point matched to it (nullptr
// when none); at most one point per keypoint. Bad points are skipped.
std::vector<std::shared_ptr<map::MapPoint>> SearchByBoW(const map::KeyFrame& keyframe,
                                                        const feature::Frame& frame,
                                                        const vocab::FeatureVector& frame_features,
                                                        const BowMatchOptions& options = {});

// Matches between the map points of two keyframes: per keypoint of `keyframe1`, the map point of
// `keyframe2` matched to it (nullptr when none); each keyframe2 point is used at most once. Only
// keypoints of both keyframes that have a (good) map point take part, as in ORB-SLAM2.
std::vector<std::shared_ptr<map::MapPoint>> SearchByBoW(const map::KeyFrame& keyframe1,
                                                        const map::KeyFrame& keyframe2,
                                                        const BowMatchOptions& options = {});

// Number of non-null entries.
int CountMatches(const std::vector<std::shared_ptr<map::MapPoint>>& matches);

}  // namespace moslam::slam
