// An inverted index over bag-of-words vectors (DBoW2's Database, as ORB-SLAM2's
// KeyFrameDatabase uses it): word -> entries (keyframe ids, image ids) that contain it, so a
// query touches only entries that share a word with it. Entries are plain ids: the covisibility
// logic of relocalization and loop detection lives in slam/, which knows keyframes.
//
// Not thread-safe: the owner serializes access (slam/ holds it under the map mutex).
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "moslam/vocab/bow.h"

namespace moslam::vocab {

struct QueryResult {
  uint64_t id = 0;
  double score = 0.0;  // Vocabulary::Score of query and entry
  int shared_words = 0;
};

class Database {
 public:
  void Add(uint64_t id, const BowVector& bow);
  // Removes every posting of `id`; the stored vector is used, so `bow` only documents intent.
  // Erasing an unknown id does nothing. Adding an id again replaces its entry.
  void Erase(uint64_t id, const BowVector& bow);
  void Clear();
  size_t size() const { return bows_.size(); }
  const BowVector* Find(uint64_t id) const;

  // Entries sharing at least one word with `query`, with how many (ORB-SLAM2's first pass).
  std::vector<std::pair<uint64_t, int>> SharingWords(const BowVector& query) const;
  // The `max_results` best entries by score (ties: lower id first), among those sharing at
  // least `min_shared_fraction` of the best entry's shared-word count (ORB-SLAM2 uses 0.8).
  // max_results < 0: all of them.
  std::vector<QueryResult> Query(const BowVector& query, int max_results,
                                 double min_shared_fraction = 0.0) const;

 private:
  std::unordered_map<WordId, std::vector<uint64_t>> postings_;
  std::unordered_map<uint64_t, BowVector> bows_;
};

}  // namespace moslam::vocab
