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

#include <map>
#include <memory>
#include <unordered_map>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/map/keyframe.h"
#include "moslam/vocab/bow.h"
#include "moslam/vocab/database.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::slam {

// The direct-index level: ORB-SLAM2 calls DBoW2 with `levelsup` = 4 on its 6-level, k = 10
// vocabulary, i.e. groups features by the k^2 = 100 nodes two below the root, level 1 in
// vocab::Vocabulary::Transform's numbering (root's children = 0). The grouping is what decides
// which features SearchByBoW compares, so the same level 1 is used for any tree of 3 or more
// levels (the shipped 5-level one included, where levelsup = 4 would leave 10 groups;
// docs/VOCABULARY.md), and level 0 for shallower test trees.
int DirectIndexLevel(const vocab::Vocabulary& vocabulary);

// Down-weighting of repeated structure in loop queries. A word that the places passed a short
// while ago also hold (a street of identical houses, a corridor of identical doors) says little
// about *which* place the camera is at: the same idea as the inverse document frequency of the
// vocabulary (Sivic & Zisserman 2003), but over the recent trajectory rather than the training
// images, like the burstiness weighting of Jegou et al. (CVPR 2009) across images. Each word's
// weight is multiplied by log((m + 1) / (c + 1)) / log(m + 1), where c of the m recent
// keyframes hold it (1 for a word none of them holds, 0 for one all of them hold), and the
// vector is L1-normalized again. Default-constructed: the identity (m = 0).
class RecentWordWeights {
 public:
  RecentWordWeights() = default;
  // `counts`: word -> number of the `keyframes` recent keyframes whose BoW holds it.
  RecentWordWeights(std::unordered_map<vocab::WordId, int> counts, int keyframes);
  int keyframes() const { return keyframes_; }
  double Factor(vocab::WordId word) const;  // in [0, 1]
  // `bow` with every word's weight times its factor, L1-normalized (empty when nothing is left).
  vocab::BowVector Apply(const vocab::BowVector& bow) const;

 private:
  std::unordered_map<vocab::WordId, int> counts_;
  int keyframes_ = 0;
};

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

  // Indexes the keyframe by its bow (ComputeBow first); a keyframe with an empty bow (no
  // features, or only zero-weight words) is not indexed. Adding twice is a no-op.
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
  // Scores are taken on both vectors reweighted by `weights` (identity by default).
  std::vector<std::shared_ptr<map::KeyFrame>> DetectLoopCandidates(
      const map::KeyFrame& keyframe, double min_score,
      const RecentWordWeights& weights = RecentWordWeights()) const;

  // The lowest BoW score between `keyframe` and its connected keyframes (ORB-SLAM2's
  // LoopClosing::DetectLoop minScore); 1 when it has none. Keyframes without BoW are skipped.
  double MinCovisibleScore(const map::KeyFrame& keyframe,
                           const RecentWordWeights& weights = RecentWordWeights()) const;

  // The word weights of the recent past of `keyframe`: its `num_keyframes` indexed predecessors
  // (highest ids below its own) that are not connected to it in the covisibility graph, i.e.
  // places passed a while ago and out of view now. Fewer than `min_keyframes` of them (the start
  // of a run): the identity, as counts over a handful of keyframes say nothing.
  RecentWordWeights RecentPastWeights(const map::KeyFrame& keyframe, int num_keyframes,
                                      int min_keyframes) const;

 private:
  struct Scored {
    std::shared_ptr<map::KeyFrame> keyframe;
    double score = 0.0;
  };
  // Shared-word counts, min-common-words filter and scores: the first steps of both queries.
  // `exclude(kf)` drops keyframes before counting.
  template <typename Exclude>
  std::unordered_map<uint64_t, Scored> ScoreSharing(const vocab::BowVector& bow, Exclude exclude,
                                                    const RecentWordWeights& weights) const;
  // Covisibility accumulation and the 0.75 x best filter.
  static std::vector<std::shared_ptr<map::KeyFrame>> Accumulate(
      const std::unordered_map<uint64_t, Scored>& scored, double min_score);

  std::shared_ptr<const vocab::Vocabulary> vocabulary_;
  int direct_index_level_ = 0;
  vocab::Database index_;
  std::map<uint64_t, std::weak_ptr<map::KeyFrame>> keyframes_;  // by id: recent ones last
};

}  // namespace moslam::slam
