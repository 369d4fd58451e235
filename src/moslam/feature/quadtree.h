// Spatial distribution of keypoint candidates with a quadtree, the "octree" of ORB-SLAM2's
// ORBextractor (Mur-Artal & Tardós 2017): the region is split into quadrants, always splitting
// the nodes that hold the most candidates, until there are as many non-empty nodes as keypoints
// wanted; then each node keeps its strongest candidate. Compared with keeping the globally
// strongest corners, this spreads keypoints over the whole image, which helps pose estimation.
#pragma once

#include <vector>

namespace moslam::feature {

// A keypoint candidate in the coordinates of one pyramid level.
struct Candidate {
  float x = 0;
  float y = 0;
  float response = 0;  // FAST score: larger is stronger
};

// Reusable: keeps its node pool between calls so that per-frame distribution allocates nothing
// once warmed up. Not thread-safe; use one per thread.
class QuadtreeDistributor {
 public:
  // Selects min(wanted, candidates.size()) candidates spread over the rectangle
  // [min_x, max_x) x [min_y, max_y) (which must contain every candidate) and writes them to
  // *selected, ordered by (y, x). Reorders *candidates (the tree partitions them in place).
  // Differences from ORB-SLAM2, both to make the result exact and reproducible: when the last
  // split overshoots `wanted`, the nodes with the weakest best candidates are dropped; ties (equal
  // counts, equal responses) are broken by position.
  void Distribute(std::vector<Candidate>* candidates, float min_x, float max_x, float min_y,
                  float max_y, int wanted, std::vector<Candidate>* selected);

 private:
  struct Node {
    float x0, y0, x1, y1;  // bounds, [x0, x1) x [y0, y1)
    int begin, end;        // range in points_
    int size() const { return end - begin; }
  };
  bool Expandable(const Node& node) const;
  // Appends the non-empty quadrants of `node` to *out and returns how many were appended.
  int Split(const Node& node, std::vector<Node>* out);
  void InitialNodes(float min_x, float max_x, float min_y, float max_y);
  void SplitAll();
  void SplitLargestUntil(int wanted);
  void SelectBest(int wanted, std::vector<Candidate>* selected);

  Candidate* points_ = nullptr;    // the candidates of the current call, grouped by node
  std::vector<Candidate> sorted_;  // counting-sort target for the initial nodes
  std::vector<Node> nodes_;
  std::vector<Node> next_;
  std::vector<int> by_size_;     // node indices, for splitting the largest first
  std::vector<char> removed_;    // per node of nodes_, during SplitLargestUntil
  std::vector<int> best_;        // per node: position of its strongest candidate
  std::vector<int> bucket_end_;  // counting sort of the initial nodes
  std::vector<int> cursor_;
};

}  // namespace moslam::feature
