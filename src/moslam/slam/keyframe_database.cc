#include "moslam/slam/keyframe_database.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "moslam/util/check.h"

namespace moslam::slam {

int DirectIndexLevel(const vocab::Vocabulary& vocabulary) {
  return vocabulary.levels() >= 3 ? 1 : 0;
}

RecentWordWeights::RecentWordWeights(std::unordered_map<vocab::WordId, int> counts, int keyframes)
    : counts_(std::move(counts)), keyframes_(keyframes) {
  MOSLAM_CHECK(keyframes_ >= 0);
}

double RecentWordWeights::Factor(vocab::WordId word) const {
  if (keyframes_ == 0) return 1.0;
  const auto it = counts_.find(word);
  const int c = it == counts_.end() ? 0 : std::min(it->second, keyframes_);
  const double m1 = static_cast<double>(keyframes_) + 1.0;
  return std::log(m1 / (static_cast<double>(c) + 1.0)) / std::log(m1);
}

vocab::BowVector RecentWordWeights::Apply(const vocab::BowVector& bow) const {
  if (keyframes_ == 0) return bow;
  vocab::BowVector out;
  double sum = 0.0;
  for (const auto& [word, value] : bow) {
    const double v = value * Factor(word);
    if (v == 0.0) continue;
    out.emplace_hint(out.end(), word, v);
    sum += std::abs(v);
  }
  if (sum > 0.0) {
    for (auto& entry : out) entry.second /= sum;
  }
  return out;
}

KeyFrameDatabase::KeyFrameDatabase(std::shared_ptr<const vocab::Vocabulary> vocabulary)
    : vocabulary_(std::move(vocabulary)) {
  MOSLAM_CHECK(vocabulary_ != nullptr && !vocabulary_->empty());
  direct_index_level_ = DirectIndexLevel(*vocabulary_);
}

KeyFrameBow KeyFrameDatabase::ComputeBow(const cv::Mat& descriptors) const {
  KeyFrameBow out;
  if (descriptors.rows == 0) return out;
  vocabulary_->Transform(descriptors, &out.bow, &out.features, direct_index_level_);
  return out;
}

void KeyFrameDatabase::ComputeBow(map::KeyFrame* keyframe) const {
  if (!keyframe->bow.empty()) return;
  KeyFrameBow b = ComputeBow(keyframe->frame.descriptors);
  keyframe->bow = std::move(b.bow);
  keyframe->bow_features = std::move(b.features);
}

void KeyFrameDatabase::Add(const std::shared_ptr<map::KeyFrame>& keyframe) {
  MOSLAM_CHECK(keyframe != nullptr);
  // An empty BoW (no features, or only words of weight 0, which every training image had)
  // shares no word with anything: nothing to index.
  if (keyframe->bow.empty()) return;
  if (!keyframes_.emplace(keyframe->id, keyframe).second) return;
  index_.Add(keyframe->id, keyframe->bow);
}

void KeyFrameDatabase::Erase(const map::KeyFrame& keyframe) {
  if (keyframes_.erase(keyframe.id) == 0) return;
  index_.Erase(keyframe.id, keyframe.bow);
}

void KeyFrameDatabase::Clear() {
  keyframes_.clear();
  index_.Clear();
}

template <typename Exclude>
std::unordered_map<uint64_t, KeyFrameDatabase::Scored> KeyFrameDatabase::ScoreSharing(
    const vocab::BowVector& bow, Exclude exclude, const RecentWordWeights& weights) const {
  std::vector<std::pair<std::shared_ptr<map::KeyFrame>, int>> sharing;
  int max_common = 0;
  for (const auto& [id, common] : index_.SharingWords(bow)) {
    auto it = keyframes_.find(id);
    if (it == keyframes_.end()) continue;
    auto kf = it->second.lock();
    if (!kf || kf->bad() || exclude(*kf)) continue;
    sharing.emplace_back(std::move(kf), common);
    max_common = std::max(max_common, common);
  }
  // ORB-SLAM2: int minCommonWords = maxCommonWords * 0.8f, then strictly more than that.
  const int min_common = static_cast<int>(static_cast<float>(max_common) * 0.8f);
  std::unordered_map<uint64_t, Scored> scored;
  const vocab::BowVector weighted = weights.Apply(bow);
  for (auto& [kf, common] : sharing) {
    if (common <= min_common) continue;
    const double score = weights.keyframes() == 0
                             ? vocab::Vocabulary::Score(bow, kf->bow)
                             : vocab::Vocabulary::Score(weighted, weights.Apply(kf->bow));
    scored[kf->id] = Scored{kf, score};
  }
  return scored;
}

std::vector<std::shared_ptr<map::KeyFrame>> KeyFrameDatabase::Accumulate(
    const std::unordered_map<uint64_t, Scored>& scored, double min_score) {
  // Visit in id order so that ties resolve the same way every run.
  std::map<uint64_t, const Scored*> ordered;
  for (const auto& [id, s] : scored) ordered[id] = &s;
  struct Group {
    double accumulated;
    std::shared_ptr<map::KeyFrame> best;
  };
  std::vector<Group> groups;
  double best_accumulated = 0.0;
  for (const auto& [id, s] : ordered) {
    if (s->score < min_score) continue;
    double accumulated = s->score;
    const Scored* best = s;
    // Only neighbours that passed the shared-words filter have a score (ORB-SLAM2's loop query
    // checks this; its relocalization query reads a stale score otherwise).
    for (const auto& neighbour : s->keyframe->BestCovisibles(10)) {
      auto it = scored.find(neighbour->id);
      if (it == scored.end()) continue;
      accumulated += it->second.score;
      if (it->second.score > best->score) best = &it->second;
    }
    groups.push_back({accumulated, best->keyframe});
    best_accumulated = std::max(best_accumulated, accumulated);
  }
  std::stable_sort(groups.begin(), groups.end(), [](const Group& a, const Group& b) {
    if (a.accumulated != b.accumulated) return a.accumulated > b.accumulated;
    return a.best->id < b.best->id;
  });
  const double min_accumulated = 0.75 * best_accumulated;
  std::vector<std::shared_ptr<map::KeyFrame>> out;
  std::vector<uint64_t> seen;
  for (const Group& g : groups) {
    if (!(g.accumulated > min_accumulated)) break;  // sorted: the rest are lower
    if (std::find(seen.begin(), seen.end(), g.best->id) != seen.end()) continue;
    seen.push_back(g.best->id);
    out.push_back(g.best);
  }
  return out;
}

std::vector<std::shared_ptr<map::KeyFrame>> KeyFrameDatabase::DetectRelocalizationCandidates(
    const vocab::BowVector& frame_bow) const {
  if (frame_bow.empty()) return {};
  return Accumulate(ScoreSharing(
                        frame_bow, [](const map::KeyFrame&) { return false; }, RecentWordWeights()),
                    0.0);
}

std::vector<std::shared_ptr<map::KeyFrame>> KeyFrameDatabase::DetectLoopCandidates(
    const map::KeyFrame& keyframe, double min_score, const RecentWordWeights& weights) const {
  if (keyframe.bow.empty()) return {};
  const auto& connected = keyframe.connection_weights();
  const auto exclude = [&](const map::KeyFrame& kf) {
    return kf.id == keyframe.id || connected.count(kf.id) > 0;
  };
  return Accumulate(ScoreSharing(keyframe.bow, exclude, weights), min_score);
}

double KeyFrameDatabase::MinCovisibleScore(const map::KeyFrame& keyframe,
                                           const RecentWordWeights& weights) const {
  double min_score = 1.0;
  const vocab::BowVector weighted = weights.Apply(keyframe.bow);
  for (const auto& kf : keyframe.BestCovisibles(-1)) {
    if (kf->bow.empty()) continue;
    min_score = std::min(min_score, vocab::Vocabulary::Score(weighted, weights.Apply(kf->bow)));
  }
  return min_score;
}

RecentWordWeights KeyFrameDatabase::RecentPastWeights(const map::KeyFrame& keyframe,
                                                      int num_keyframes, int min_keyframes) const {
  MOSLAM_CHECK(num_keyframes >= 0 && min_keyframes >= 0);
  const auto& connected = keyframe.connection_weights();
  std::unordered_map<vocab::WordId, int> counts;
  int found = 0;
  for (auto it = keyframes_.lower_bound(keyframe.id);
       it != keyframes_.begin() && found < num_keyframes;) {
    --it;
    if (connected.count(it->first) > 0) continue;
    const auto kf = it->second.lock();
    if (!kf || kf->bad()) continue;
    for (const auto& entry : kf->bow) ++counts[entry.first];
    ++found;
  }
  if (found == 0 || found < min_keyframes) return RecentWordWeights();
  return RecentWordWeights(std::move(counts), found);
}

}  // namespace moslam::slam
