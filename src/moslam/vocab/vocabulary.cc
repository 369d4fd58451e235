#include "moslam/vocab/vocabulary.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "moslam/feature/descriptor_distance.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::vocab {

void VocabularyTrainOptions::Check() const {
  if (k < 2 || k > 64) ThrowInput("vocabulary option k must be in [2, 64], got {}", k);
  if (levels < 1 || levels > 10) {
    ThrowInput("vocabulary option levels must be in [1, 10], got {}", levels);
  }
  if (std::pow(static_cast<double>(k), levels) > 2.0e9) {
    ThrowInput("vocabulary options k = {}, levels = {}: k^levels must stay below 2e9 words", k,
               levels);
  }
  if (max_iterations < 1 || max_iterations > 1000) {
    ThrowInput("vocabulary option max_iterations must be in [1, 1000], got {}", max_iterations);
  }
  if (num_threads < 1 || num_threads > 256) {
    ThrowInput("vocabulary option num_threads must be in [1, 256], got {}", num_threads);
  }
}

size_t Vocabulary::size() const { return words_.size(); }

double Vocabulary::Weight(WordId word) const {
  MOSLAM_CHECK_LT(word, words_.size());
  return nodes_[words_[word]].weight;
}

const uint8_t* Vocabulary::WordDescriptor(WordId word) const {
  MOSLAM_CHECK_LT(word, words_.size());
  return nodes_[words_[word]].descriptor;
}

NodeId Vocabulary::WordNode(WordId word) const {
  MOSLAM_CHECK_LT(word, words_.size());
  return words_[word];
}

NodeId Vocabulary::AncestorAtLevel(NodeId node, int direct_index_level) const {
  MOSLAM_CHECK_LT(node, nodes_.size());
  const int depth = std::max(direct_index_level, 0) + 1;
  while (nodes_[node].depth > depth) node = nodes_[node].parent;
  return node;
}

int Vocabulary::DirectIndexLevelFromLeaves(int levels_up) const {
  // DBoW2 stores the node at depth L - levels_up (root = depth 0); our levels start at depth 1.
  return std::max(levels_ - levels_up - 1, 0);
}

WordId Vocabulary::Descend(const uint8_t* descriptor, int direct_index_level,
                           NodeId* level_node) const {
  MOSLAM_CHECK(!nodes_.empty()) << "Transform on an empty vocabulary";
  const int index_depth = std::max(direct_index_level, 0) + 1;
  uint32_t node = 0;
  while (!nodes_[node].children.empty()) {
    const std::vector<uint32_t>& children = nodes_[node].children;
    uint32_t best = children[0];
    int best_distance = std::numeric_limits<int>::max();
    for (uint32_t child : children) {
      const int d = feature::DescriptorDistance(descriptor, nodes_[child].descriptor);
      if (d < best_distance) {  // strict: the first of equally near children wins
        best_distance = d;
        best = child;
      }
    }
    node = best;
    if (nodes_[node].depth <= index_depth && level_node != nullptr) *level_node = node;
  }
  return static_cast<WordId>(nodes_[node].word_id);
}

WordId Vocabulary::Transform(const uint8_t* descriptor) const {
  return Descend(descriptor, 0, nullptr);
}

void Vocabulary::Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* features,
                           int direct_index_level) const {
  MOSLAM_CHECK(bow != nullptr);
  bow->clear();
  if (features != nullptr) features->clear();
  if (descriptors.empty()) return;
  if (descriptors.type() != CV_8UC1 || descriptors.cols != 32) {
    ThrowInput("Vocabulary::Transform needs CV_8UC1 N x 32 descriptors, got type {} with {} cols",
               descriptors.type(), descriptors.cols);
  }
  for (int i = 0; i < descriptors.rows; ++i) {
    NodeId level_node = 0;
    const WordId word = Descend(descriptors.ptr<uint8_t>(i), direct_index_level, &level_node);
    const double weight = nodes_[words_[word]].weight;
    // TF-IDF: summing the IDF once per occurrence gives tf * idf up to the 1/n factor, which
    // the L1 normalization below removes (DBoW2, TF_IDF weighting).
    if (weight <= 0.0) continue;
    (*bow)[word] += weight;
    if (features != nullptr) (*features)[level_node].push_back(static_cast<uint32_t>(i));
  }
  double norm = 0.0;
  for (const auto& [word, value] : *bow) norm += std::abs(value);
  if (norm > 0.0) {
    for (auto& [word, value] : *bow) value /= norm;
  }
}

double Vocabulary::Score(const BowVector& a, const BowVector& b) {
  // DBoW2's L1Scoring on normalized vectors: 1 - |a - b|_1 / 2 = sum over the common words of
  // (|a_i| + |b_i| - |a_i - b_i|) / 2, so one merge pass over the two sorted maps suffices.
  double sum = 0.0;
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->first < ib->first) {
      ++ia;
    } else if (ib->first < ia->first) {
      ++ib;
    } else {
      const double x = ia->second;
      const double y = ib->second;
      sum += std::abs(x) + std::abs(y) - std::abs(x - y);
      ++ia;
      ++ib;
    }
  }
  return sum / 2.0;
}

void Vocabulary::IndexWords(const std::string& source) {
  words_.clear();
  if (nodes_.empty()) return;
  nodes_[0].depth = 0;
  for (size_t i = 1; i < nodes_.size(); ++i) {
    Node& node = nodes_[i];
    if (node.parent >= i) {
      ThrowInFile(source,
                  fmt::format("node {} has parent {}, which does not precede it", i, node.parent));
    }
    node.depth = static_cast<uint16_t>(nodes_[node.parent].depth + 1);
    if (node.depth > levels_) {
      ThrowInFile(source, fmt::format("node {} is at depth {}, deeper than the {} levels", i,
                                      node.depth, levels_));
    }
  }
  if (nodes_[0].children.empty()) ThrowInFile(source, "the vocabulary has no words");
  for (size_t i = 1; i < nodes_.size(); ++i) {
    Node& node = nodes_[i];
    if (node.children.empty()) {
      node.word_id = static_cast<int32_t>(words_.size());
      words_.push_back(static_cast<uint32_t>(i));
    } else {
      node.word_id = -1;
    }
  }
}

}  // namespace moslam::vocab
