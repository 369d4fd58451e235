#include "moslam/vocab/database.h"

#include <algorithm>

#include "moslam/util/check.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {

void Database::Add(uint64_t id, const BowVector& bow) {
  if (bows_.count(id) != 0) Erase(id, bows_.at(id));  // re-adding replaces the entry
  for (const auto& [word, value] : bow) postings_[word].push_back(id);
  bows_.emplace(id, bow);
}

void Database::Erase(uint64_t id, const BowVector& bow) {
  auto entry = bows_.find(id);
  if (entry == bows_.end()) return;
  // The stored vector is the one the postings were made from, whatever the caller passes.
  (void)bow;
  for (const auto& [word, value] : entry->second) {
    auto posting = postings_.find(word);
    MOSLAM_CHECK(posting != postings_.end()) << "no posting of word " << word << " for " << id;
    std::vector<uint64_t>& ids = posting->second;
    ids.erase(std::remove(ids.begin(), ids.end(), id), ids.end());
    if (ids.empty()) postings_.erase(posting);
  }
  bows_.erase(entry);
}

void Database::Clear() {
  postings_.clear();
  bows_.clear();
}

const BowVector* Database::Find(uint64_t id) const {
  auto entry = bows_.find(id);
  return entry == bows_.end() ? nullptr : &entry->second;
}

std::vector<std::pair<uint64_t, int>> Database::SharingWords(const BowVector& query) const {
  std::unordered_map<uint64_t, int> counts;
  for (const auto& [word, value] : query) {
    auto posting = postings_.find(word);
    if (posting == postings_.end()) continue;
    for (uint64_t id : posting->second) ++counts[id];
  }
  std::vector<std::pair<uint64_t, int>> result(counts.begin(), counts.end());
  std::sort(result.begin(), result.end());  // by id: the order must not depend on hashing
  return result;
}

std::vector<QueryResult> Database::Query(const BowVector& query, int max_results,
                                         double min_shared_fraction) const {
  const std::vector<std::pair<uint64_t, int>> sharing = SharingWords(query);
  int max_shared = 0;
  for (const auto& [id, shared] : sharing) max_shared = std::max(max_shared, shared);
  const double min_shared = min_shared_fraction * max_shared;
  std::vector<QueryResult> results;
  for (const auto& [id, shared] : sharing) {
    if (shared < min_shared) continue;
    results.push_back({id, Vocabulary::Score(query, bows_.at(id)), shared});
  }
  std::sort(results.begin(), results.end(), [](const QueryResult& a, const QueryResult& b) {
    return a.score != b.score ? a.score > b.score : a.id < b.id;
  });
  if (max_results >= 0 && results.size() > static_cast<size_t>(max_results)) {
    results.resize(static_cast<size_t>(max_results));
  }
  return results;
}

}  // namespace moslam::vocab
