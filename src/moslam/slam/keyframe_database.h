// The keyframe database (ORB-SLAM2's KeyFrameDatabase, Mur-Artal & Tardós 2017; place recognition
// with DBoW2, Gálvez-López & Tardós 2012): an inverted index of the keyframes' bag-of-words
// vectors (vocab::Database) and the two queries built on it and on the covisibility graph:
// relocalization candidates for a lost frame and loop candidates for a new keyframe.
//
// Life cycle: local mapping computes a keyframe's BoW (ComputeBow, ORB-SLAM2's ComputeBoW in
// ProcessNewKeyFrame) and adds it after inserting it; Map::EraseKeyFrame (culling) erases it
// through the map's erase listener, as ORB-SLAM2's KeyFrame::SetBadFlag does.
//
// Locking: the database is part of the map's state. Hold Map::mutex() for Add, Erase and the
// Detect* queries (they read keyframes' covisibility). ComputeBow only reads the immutable
// vocabulary and may run without any lock.
//
//   KeyFrameDatabase db(vocabulary);
//   KeyFrameBow b = db.ComputeBow(frame.descriptors);                 // no lock
//   std::lock_guard<std::mutex> lock(map.mutex());
//   auto candidates = db.DetectRelocalizationCandidates(b.bow);
//   auto loops = db.DetectLoopCandidates(*kf, db.MinCovisibleScore(*kf));
#pragma once

#include <memory>
#include <unordered_map>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/map/keyframe.h"
#include "moslam/vocab/bow.h"
#include "moslam/vocab/database.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::slam {

// ORB-SLAM2 builds the direct index 4 levels above the leaves (DBoW2's `levelsup` = 4: on its
// 6-level, k = 10 vocabulary the nodes at depth 2, ~100 of them). In vocab::Vocabulary::Transform's
// numbering (root's children = 0) that is levels() - 5; shallower trees (test vocabularies) use
// the root's children (0).
inline constexpr int kDirectIndexLevelsUp = 4;
int DirectIndexLevel(const vocab::Vocabulary& vocabulary);

struct KeyFrameBow {
  vocab::BowVector bow;
  vocab::FeatureVector features;  // direct index at DirectIndexLevel
};

class KeyFrameDatabase {
 public:
  // `vocabulary` must be non-empty (CHECK).
  explicit KeyFrameDatabase(std::shared_ptr<const vocab::Vocabulary> vocabulary);

  const std::shared_ptr<const vocab::Vocabulary>& vocabulary() const { return vocabulary_; }

  // BoW vector and direct index of one image's descriptors (N x 32 CV_8U). No lock needed.
  KeyFrameBow ComputeBow(const cv::Mat& descriptors) const;
  // Sets keyframe->bow / bow_features from its descriptors when not yet set (writes the
  // keyframe: hold Map::mutex()).
  void ComputeBow(map::KeyFrame* keyframe) const;

  // Indexes the keyframe; its bow must be set (CHECK), unless it has no features at all (then
  // there is nothing to index). Adding twice is a no-op.
  void Add(const std::shared_ptr<map::KeyFrame>& keyframe);
  // Removes it (no-op when not indexed).
  void Erase(const map::KeyFrame& keyframe);
  void Clear();
  size_t size() const { return keyframes_.size(); }
  bool Contains(uint64_t keyframe_id) const { return keyframes_.count(keyframe_id) > 0; }

  // ORB-SLAM2's DetectRelocalizationCandidates: keyframes sharing words with `frame_bow`; those
  // sharing more than 0.8 x the most shared words are scored; each scored keyframe's score is
  // accumulated over its 10 best covisibles (those scored), and the best-scoring keyframe of
  // each group whose accumulated score exceeds 0.75 x the best accumulated score is returned
  // (once), ordered by accumulated score (highest first, ties by id).
  std::vector<std::shared_ptr<map::KeyFrame>> DetectRelocalizationCandidates(
      const vocab::BowVector& frame_bow) const;

  // ORB-SLAM2's DetectLoopCandidates: as above for a keyframe's BoW, among keyframes that are
  // not `keyframe` itself nor connected to it in the covisibility graph, keeping only scores
  // >= `min_score` before accumulating (ORB-SLAM2's minScore: MinCovisibleScore(keyframe)).
  std::vector<std::shared_ptr<map::KeyFrame>> DetectLoopCandidates(const map::KeyFrame& keyframe,
                                                                   double min_score) const;

  // The lowest BoW score between `keyframe` and its connected keyframes (ORB-SLAM2's
  // LoopClosing::DetectLoop minScore); 1 when it has none. Keyframes without BoW are skipped.
  double MinCovisibleScore(const map::KeyFrame& keyframe) const;

 private:
  struct Scored {
    std::shared_ptr<map::KeyFrame> keyframe;
    double score = 0.0;
  };
  // Shared-word counts, min-common-words filter and scores: the first steps of both queries.
  // `exclude(kf)` drops keyframes before counting.
  template <typename Exclude>
  std::unordered_map<uint64_t, Scored> ScoreSharing(const vocab::BowVector& bow,
                                                    Exclude exclude) const;
  // Covisibility accumulation and the 0.75 x best filter.
  static std::vector<std::shared_ptr<map::KeyFrame>> Accumulate(
      const std::unordered_map<uint64_t, Scored>& scored, double min_score);

  std::shared_ptr<const vocab::Vocabulary> vocabulary_;
  int direct_index_level_ = 0;
  vocab::Database index_;
  std::unordered_map<uint64_t, std::weak_ptr<map::KeyFrame>> keyframes_;
};

}  // namespace moslam::slam
