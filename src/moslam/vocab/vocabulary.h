// A hierarchical vocabulary of binary ORB descriptors (Nistér & Stewénius 2006, vocabulary tree;
// Gálvez-López & Tardós 2012, DBoW2 for binary descriptors): k-medians in Hamming space with
// k-means++ seeding, `levels` deep, k children per node; leaves are the words, weighted by
// inverse document frequency over the training images; images are scored by the L1 distance of
// their normalized TF-IDF vectors.
//
//   Vocabulary voc = Vocabulary::Train(descriptors_per_image, options);   // or Load(path)
//   voc.Save("orb_vocab.mvoc");                      // compact binary, loads in milliseconds
//   BowVector bow; FeatureVector fv;
//   voc.Transform(frame.descriptors, &bow, &fv, /*direct_index_level=*/4);
//   double s = voc.Score(bow_a, bow_b);              // 1 = identical, 0 = nothing shared
//
// Thread safety: a built or loaded Vocabulary is immutable; all const members may be called
// concurrently.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/vocab/bow.h"

namespace moslam::vocab {

struct VocabularyTrainOptions {
  int k = 10;               // children per node (branching factor)
  int levels = 6;           // depth of the tree; up to k^levels words
  int max_iterations = 10;  // k-medians iterations per node (stops earlier when stable)
  uint64_t seed = 1;        // k-means++ seeding
  int num_threads = 1;      // nodes of one level are clustered in parallel
  void Check() const;       // InputError naming the field
};

class Vocabulary {
 public:
  Vocabulary() = default;  // empty: size() == 0, Transform not allowed

  // `descriptors`: one CV_8UC1 N x 32 matrix per training image (rows = ORB descriptors).
  // `progress` (may be empty) is called with the fraction done in [0, 1], from the calling
  // thread or (num_threads > 1) from workers, never concurrently. Deterministic for a seed,
  // whatever num_threads. Throws InputError on malformed descriptors or options.
  static Vocabulary Train(const std::vector<cv::Mat>& descriptors,
                          const VocabularyTrainOptions& options,
                          const std::function<void(double)>& progress = {});

  // Loads this project's binary format or an ORB-SLAM2/DBoW2 text vocabulary (ORBvoc.txt),
  // detected from the content. Throws InputError naming the file on anything malformed.
  static Vocabulary Load(const std::string& path);
  // Compact binary format (docs/VOCABULARY.md): header, then per node its descriptor, parent
  // and, for words, the IDF weight.
  void Save(const std::string& path) const;

  // The word of one 32-byte descriptor: descend from the root to the nearest child (Hamming).
  WordId Transform(const uint8_t* descriptor) const;
  // TF-IDF vector of an image (L1-normalized) and its direct index at `direct_index_level`
  // (levels counted from the root's children = 0 ... levels-1; a word shallower than that level
  // is its own node). ORB-SLAM2 calls DBoW2 with levelsup = 4 on its 6-level tree, i.e. nodes
  // two below the root: level 1 here, DirectIndexLevelFromLeaves(4) in general. Features whose
  // word has weight 0 (seen in every training image) are left out of both, as in DBoW2.
  // `descriptors`: CV_8UC1 N x 32 (N may be 0). `features` may be null.
  void Transform(const cv::Mat& descriptors, BowVector* bow, FeatureVector* features,
                 int direct_index_level) const;
  // DBoW2's `levelsup` (levels up from the leaves) as a direct_index_level, at least 0.
  int DirectIndexLevelFromLeaves(int levels_up) const;
  // L1 score of two normalized vectors: 1 - 0.5 * |a - b|_1, in [0, 1] (DBoW2's L1Scoring).
  static double Score(const BowVector& a, const BowVector& b);

  size_t size() const;  // number of words
  int k() const { return k_; }
  int levels() const { return levels_; }
  double Weight(WordId word) const;  // IDF weight of a word
  bool empty() const { return size() == 0; }
  size_t num_nodes() const { return nodes_.size(); }  // including the root
  // The 32-byte centroid of a word (binary median of its training descriptors).
  const uint8_t* WordDescriptor(WordId word) const;
  // The node of `word` and that node's ancestor at `direct_index_level` (as in Transform).
  NodeId WordNode(WordId word) const;
  NodeId AncestorAtLevel(NodeId node, int direct_index_level) const;

 private:
  struct Node {
    uint32_t parent = 0;
    std::vector<uint32_t> children;
    uint8_t descriptor[32] = {};
    double weight = 0.0;   // IDF (words only)
    int32_t word_id = -1;  // >= 0 for leaves
    uint16_t depth = 0;    // root 0, its children 1, ...
  };
  int k_ = 0;
  int levels_ = 0;
  std::vector<Node> nodes_;      // nodes_[0] = root
  std::vector<uint32_t> words_;  // word id -> node index
  // Descends to a word; *level_node = the node at direct_index_level on the way (if not null).
  WordId Descend(const uint8_t* descriptor, int direct_index_level, NodeId* level_node) const;
  // Fills words_ from the leaves in node order and checks the tree (loading, training).
  void IndexWords(const std::string& source);
  void LoadBinary(const std::string& path, const std::string& bytes);
  void LoadDbow2Text(const std::string& path, const std::string& bytes);
  friend class VocabularyBuilder;
};

}  // namespace moslam::vocab
