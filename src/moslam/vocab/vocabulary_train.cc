// Training of the vocabulary tree: hierarchical k-medians in Hamming space (DBoW2's HKmeansStep,
// Gálvez-López & Tardós 2012) with k-means++ seeding (Arthur & Vassilvitskii 2007), then IDF
// weights over the training images.
//
// Hand-written rather than cv::kmeans: OpenCV clusters in Euclidean space on floats, whereas
// binary descriptors need Hamming distances and per-bit majority centres (the k-medians of the
// Hamming metric), and we need a deterministic tree whatever the number of threads.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <mutex>
#include <thread>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/vocab/vocabulary.h"

namespace moslam::vocab {
namespace {

using Descriptor = std::array<uint8_t, 32>;

// SplitMix64 (Steele et al. 2014): a tiny generator whose output is the same on every platform,
// unlike std::uniform_int_distribution.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t Next() {
    uint64_t z = (state_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }  // [0, 1)

 private:
  uint64_t state_;
};

struct Cluster {
  Descriptor center{};
  std::vector<uint32_t> members;  // indices into the training descriptors
};

class KMedians {
 public:
  KMedians(const std::vector<const uint8_t*>& data, int k, int max_iterations)
      : data_(data), k_(k), max_iterations_(max_iterations) {}

  // Clusters `members` into at most k groups; fewer when there are fewer distinct descriptors.
  std::vector<Cluster> Run(const std::vector<uint32_t>& members, uint64_t seed) const {
    std::vector<Descriptor> centers = Seed(members, seed);
    std::vector<int> assignment(members.size(), -1);
    for (int iteration = 0; iteration < max_iterations_; ++iteration) {
      if (!Assign(members, centers, &assignment) && iteration > 0) break;
      UpdateCenters(members, assignment, &centers);
    }
    // One last assignment, so that every member lies under the centre nearest to it: the
    // tree's descent then reproduces the training partition.
    Assign(members, centers, &assignment);
    std::vector<Cluster> clusters(centers.size());
    for (size_t c = 0; c < centers.size(); ++c) clusters[c].center = centers[c];
    for (size_t i = 0; i < members.size(); ++i) {
      clusters[assignment[i]].members.push_back(members[i]);
    }
    std::vector<Cluster> non_empty;
    for (Cluster& cluster : clusters) {
      if (!cluster.members.empty()) non_empty.push_back(std::move(cluster));
    }
    return non_empty;
  }

 private:
  Descriptor Copy(uint32_t index) const {
    Descriptor d;
    std::memcpy(d.data(), data_[index], 32);
    return d;
  }

  // k-means++: each further centre is drawn with probability proportional to its squared
  // distance to the nearest centre so far; stops early when every point coincides with one.
  std::vector<Descriptor> Seed(const std::vector<uint32_t>& members, uint64_t seed) const {
    Rng rng(seed);
    std::vector<Descriptor> centers;
    centers.push_back(Copy(members[rng.Next() % members.size()]));
    std::vector<double> nearest(members.size(), std::numeric_limits<double>::max());
    while (static_cast<int>(centers.size()) < k_) {
      double total = 0.0;
      for (size_t i = 0; i < members.size(); ++i) {
        const double d = feature::DescriptorDistance(data_[members[i]], centers.back().data());
        nearest[i] = std::min(nearest[i], d * d);
        total += nearest[i];
      }
      if (total <= 0.0) break;
      double target = rng.Uniform() * total;
      size_t chosen = members.size() - 1;
      for (size_t i = 0; i < members.size(); ++i) {
        target -= nearest[i];
        if (target < 0.0 && nearest[i] > 0.0) {
          chosen = i;
          break;
        }
      }
      while (nearest[chosen] <= 0.0) --chosen;  // rounding at the end: the last positive one
      centers.push_back(Copy(members[chosen]));
    }
    return centers;
  }

  // Nearest centre per member (first on ties); returns whether any assignment changed.
  bool Assign(const std::vector<uint32_t>& members, const std::vector<Descriptor>& centers,
              std::vector<int>* assignment) const {
    bool changed = false;
    for (size_t i = 0; i < members.size(); ++i) {
      int best = 0;
      int best_distance = std::numeric_limits<int>::max();
      for (size_t c = 0; c < centers.size(); ++c) {
        const int d = feature::DescriptorDistance(data_[members[i]], centers[c].data());
        if (d < best_distance) {
          best_distance = d;
          best = static_cast<int>(c);
        }
      }
      if ((*assignment)[i] != best) changed = true;
      (*assignment)[i] = best;
    }
    return changed;
  }

  // Per-bit majority of each cluster: the median in Hamming space (ties to 0). A centre that
  // lost all its members keeps its place.
  void UpdateCenters(const std::vector<uint32_t>& members, const std::vector<int>& assignment,
                     std::vector<Descriptor>* centers) const {
    const size_t num_centers = centers->size();
    std::vector<std::array<uint32_t, 256>> bit_counts(num_centers);
    std::vector<uint32_t> sizes(num_centers, 0);
    for (auto& counts : bit_counts) counts.fill(0);
    for (size_t i = 0; i < members.size(); ++i) {
      std::array<uint32_t, 256>& counts = bit_counts[assignment[i]];
      ++sizes[assignment[i]];
      const uint8_t* d = data_[members[i]];
      for (int byte = 0; byte < 32; ++byte) {
        const uint32_t value = d[byte];
        for (int bit = 0; bit < 8; ++bit) counts[byte * 8 + bit] += (value >> bit) & 1u;
      }
    }
    for (size_t c = 0; c < num_centers; ++c) {
      if (sizes[c] == 0) continue;
      Descriptor& center = (*centers)[c];
      for (int byte = 0; byte < 32; ++byte) {
        uint8_t value = 0;
        for (int bit = 0; bit < 8; ++bit) {
          if (2 * bit_counts[c][byte * 8 + bit] > sizes[c])
            value |= static_cast<uint8_t>(1u << bit);
        }
        center[byte] = value;
      }
    }
  }

  const std::vector<const uint8_t*>& data_;
  int k_;
  int max_iterations_;
};

uint64_t NodeSeed(uint64_t seed, uint32_t node) {
  Rng rng(seed ^ (0xd1b54a32d192ed03ULL * (static_cast<uint64_t>(node) + 1)));
  return rng.Next();
}

// Runs body(i) for i in [0, n) on `threads` threads (the caller's included).
template <typename Body>
void ParallelFor(size_t n, int threads, const Body& body) {
  std::atomic<size_t> next{0};
  auto worker = [&] {
    for (size_t i = next++; i < n; i = next++) body(i);
  };
  std::vector<std::thread> pool;
  const size_t extra = std::min<size_t>(static_cast<size_t>(threads) - 1, n > 0 ? n - 1 : 0);
  for (size_t t = 0; t < extra; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
}

}  // namespace

class VocabularyBuilder {
 public:
  VocabularyBuilder(const VocabularyTrainOptions& options,
                    const std::function<void(double)>& progress)
      : options_(options), progress_(progress) {}

  Vocabulary Build(const std::vector<cv::Mat>& images) {
    CollectDescriptors(images);
    Vocabulary voc;
    voc.k_ = options_.k;
    voc.levels_ = options_.levels;
    voc.nodes_.emplace_back();  // the root
    BuildTree(&voc);
    voc.IndexWords("trained vocabulary");
    SetWeights(images, &voc);
    Report(1.0);
    return voc;
  }

 private:
  struct Pending {
    uint32_t node;
    std::vector<uint32_t> members;
  };

  void CollectDescriptors(const std::vector<cv::Mat>& images) {
    for (size_t i = 0; i < images.size(); ++i) {
      const cv::Mat& m = images[i];
      if (m.empty()) continue;
      if (m.type() != CV_8UC1 || m.cols != 32) {
        ThrowInput(
            "training image {}: descriptors must be CV_8UC1 N x 32, got type {} with {} "
            "cols",
            i, m.type(), m.cols);
      }
      for (int r = 0; r < m.rows; ++r) data_.push_back(m.ptr<uint8_t>(r));
    }
    if (data_.empty()) ThrowInput("vocabulary training needs at least one descriptor");
    if (data_.size() > std::numeric_limits<uint32_t>::max()) {
      ThrowInput("vocabulary training: too many descriptors ({})", data_.size());
    }
  }

  // Level by level, so that node ids (and the seeds derived from them) do not depend on the
  // order in which threads finish.
  void BuildTree(Vocabulary* voc) {
    std::vector<Pending> pending(1);
    pending[0].node = 0;
    pending[0].members.resize(data_.size());
    for (uint32_t i = 0; i < data_.size(); ++i) pending[0].members[i] = i;
    const KMedians kmedians(data_, options_.k, options_.max_iterations);
    for (int depth = 1; depth <= options_.levels && !pending.empty(); ++depth) {
      std::vector<std::vector<Cluster>> results(pending.size());
      ParallelFor(pending.size(), options_.num_threads, [&](size_t i) {
        results[i] = kmedians.Run(pending[i].members, NodeSeed(options_.seed, pending[i].node));
        AddWork(pending[i].members.size());
      });
      std::vector<Pending> next;
      for (size_t i = 0; i < pending.size(); ++i) {
        // A node whose members are all one descriptor stays a leaf (the root never does).
        if (results[i].size() == 1 && pending[i].node != 0) continue;
        for (Cluster& cluster : results[i]) {
          const uint32_t id = static_cast<uint32_t>(voc->nodes_.size());
          voc->nodes_.emplace_back();
          Vocabulary::Node& node = voc->nodes_.back();
          node.parent = pending[i].node;
          std::memcpy(node.descriptor, cluster.center.data(), 32);
          voc->nodes_[pending[i].node].children.push_back(id);
          if (depth < options_.levels && cluster.members.size() > 1) {
            next.push_back({id, std::move(cluster.members)});
          }
        }
      }
      pending = std::move(next);
    }
  }

  // IDF = log(N / n_w): N training images, n_w of them with word w (DBoW2's TF_IDF). A word no
  // training image reaches (possible: medians move after the last assignment one level up)
  // counts as seen once.
  void SetWeights(const std::vector<cv::Mat>& images, Vocabulary* voc) {
    const size_t num_words = voc->words_.size();
    std::vector<std::vector<WordId>> image_words(images.size());
    ParallelFor(images.size(), options_.num_threads, [&](size_t i) {
      const cv::Mat& m = images[i];
      std::vector<WordId>& words = image_words[i];
      for (int r = 0; r < m.rows; ++r) words.push_back(voc->Transform(m.ptr<uint8_t>(r)));
      std::sort(words.begin(), words.end());
      words.erase(std::unique(words.begin(), words.end()), words.end());
    });
    std::vector<uint32_t> document_count(num_words, 0);
    for (const auto& words : image_words) {
      for (WordId w : words) ++document_count[w];
    }
    const double n = static_cast<double>(images.size());
    for (size_t w = 0; w < num_words; ++w) {
      voc->nodes_[voc->words_[w]].weight = std::log(n / std::max<uint32_t>(document_count[w], 1));
    }
  }

  void AddWork(size_t descriptors) {
    std::lock_guard<std::mutex> lock(progress_mutex_);
    work_done_ += descriptors;
    // Each level touches every descriptor once (fewer when branches end early); weights last.
    Report(0.95 * static_cast<double>(work_done_) /
           (static_cast<double>(data_.size()) * options_.levels));
  }

  void Report(double fraction) {
    if (progress_) progress_(std::min(fraction, 1.0));
  }

  const VocabularyTrainOptions& options_;
  const std::function<void(double)>& progress_;
  std::vector<const uint8_t*> data_;
  std::mutex progress_mutex_;
  size_t work_done_ = 0;
};

Vocabulary Vocabulary::Train(const std::vector<cv::Mat>& descriptors,
                             const VocabularyTrainOptions& options,
                             const std::function<void(double)>& progress) {
  options.Check();
  return VocabularyBuilder(options, progress).Build(descriptors);
}

}  // namespace moslam::vocab
