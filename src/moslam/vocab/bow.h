// Bag-of-words vectors (Gálvez-López & Tardós 2012, DBoW2; as ORB-SLAM2 uses them).
//
// A BowVector holds, per visual word, its TF-IDF weight in an image, L1-normalized so that
// Vocabulary::Score is in [0, 1]. A FeatureVector is the direct index: for a node at a chosen
// level of the vocabulary tree (the word's ancestor at that level), the indices of the image's
// features that fall under it, so matching two images only compares features under the same
// node (ORB-SLAM2's SearchByBoW).
#pragma once

#include <cstdint>
#include <map>
#include <vector>

namespace moslam::vocab {

using WordId = uint32_t;  // index of a leaf (word) in [0, Vocabulary::size())
using NodeId = uint32_t;  // index of a node of the tree (root = 0)

// Sorted by word (std::map), so two vectors are scored by one merge pass.
using BowVector = std::map<WordId, double>;
// Node at the direct-index level -> indices of the image's features (increasing).
using FeatureVector = std::map<NodeId, std::vector<uint32_t>>;

}  // namespace moslam::vocab
