#include "moslam/feature/quadtree.h"

#include <algorithm>
#include <cmath>

#include "moslam/util/check.h"

namespace moslam::feature {
namespace {

// Node bounds below this extent are not split again: candidates come from integer pixel
// positions, so such a node can only hold duplicates, and splitting it would never end.
constexpr float kMinNodeExtent = 0.5f;

// Strict weak order "a is the better keypoint": stronger response, then position, so that
// results do not depend on the order of equal candidates.
bool Stronger(const Candidate& a, const Candidate& b) {
  if (a.response != b.response) return a.response > b.response;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

bool RowMajor(const Candidate& a, const Candidate& b) {
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

}  // namespace

bool QuadtreeDistributor::Expandable(const Node& node) const {
  return node.size() > 1 &&
         (node.x1 - node.x0 > kMinNodeExtent || node.y1 - node.y0 > kMinNodeExtent);
}

int QuadtreeDistributor::Split(const Node& node, std::vector<Node>* out) {
  const float mx = 0.5f * (node.x0 + node.x1);
  const float my = 0.5f * (node.y0 + node.y1);
  Candidate* const first = points_ + node.begin;
  Candidate* const last = points_ + node.end;
  // Partitioning in place keeps every node's candidates contiguous (no allocation, no
  // indirection).
  Candidate* const mid_y =
      std::partition(first, last, [my](const Candidate& c) { return c.y < my; });
  Candidate* const mid_top =
      std::partition(first, mid_y, [mx](const Candidate& c) { return c.x < mx; });
  Candidate* const mid_bottom =
      std::partition(mid_y, last, [mx](const Candidate& c) { return c.x < mx; });
  auto offset = [&](const Candidate* p) { return static_cast<int>(p - points_); };
  const Node children[4] = {
      {node.x0, node.y0, mx, my, offset(first), offset(mid_top)},
      {mx, node.y0, node.x1, my, offset(mid_top), offset(mid_y)},
      {node.x0, my, mx, node.y1, offset(mid_y), offset(mid_bottom)},
      {mx, my, node.x1, node.y1, offset(mid_bottom), offset(last)},
  };
  int appended = 0;
  for (const Node& child : children) {
    if (child.size() > 0) {
      out->push_back(child);
      ++appended;
    }
  }
  return appended;
}

void QuadtreeDistributor::InitialNodes(float min_x, float max_x, float min_y, float max_y) {
  // As in ORB-SLAM2: start from roughly square nodes side by side, so that wide images (KITTI)
  // are not first split into very flat quadrants.
  const float width = max_x - min_x;
  const float height = max_y - min_y;
  const int num_initial =
      std::max(1, static_cast<int>(std::lround(width / std::max(height, 1.0f))));
  const float step = width / static_cast<float>(num_initial);
  nodes_.clear();
  if (num_initial == 1) {
    nodes_.push_back({min_x, min_y, max_x, max_y, 0, static_cast<int>(sorted_.size())});
    return;
  }
  auto bucket_of = [&](const Candidate& c) {
    return std::clamp(static_cast<int>((c.x - min_x) / step), 0, num_initial - 1);
  };
  // Counting sort of the candidates by initial node, into sorted_.
  const int n = static_cast<int>(sorted_.size());
  bucket_end_.assign(num_initial + 1, 0);
  for (int i = 0; i < n; ++i) ++bucket_end_[bucket_of(points_[i]) + 1];
  for (int b = 0; b < num_initial; ++b) bucket_end_[b + 1] += bucket_end_[b];
  cursor_.assign(bucket_end_.begin(), bucket_end_.end() - 1);
  for (int i = 0; i < n; ++i) sorted_[cursor_[bucket_of(points_[i])]++] = points_[i];
  points_ = sorted_.data();
  for (int b = 0; b < num_initial; ++b) {
    if (bucket_end_[b + 1] > bucket_end_[b]) {
      nodes_.push_back({min_x + step * static_cast<float>(b), min_y,
                        b + 1 == num_initial ? max_x : min_x + step * static_cast<float>(b + 1),
                        max_y, bucket_end_[b], bucket_end_[b + 1]});
    }
  }
}

void QuadtreeDistributor::SplitAll() {
  next_.clear();
  for (const Node& node : nodes_) {
    if (Expandable(node)) {
      Split(node, &next_);
    } else {
      next_.push_back(node);
    }
  }
  nodes_.swap(next_);
}

void QuadtreeDistributor::SplitLargestUntil(int wanted) {
  // Split the most crowded nodes first (ORB-SLAM2's second phase) and stop as soon as there are
  // enough nodes, so that the remaining budget goes where candidates are dense.
  by_size_.clear();
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) {
    if (Expandable(nodes_[i])) by_size_.push_back(i);
  }
  std::sort(by_size_.begin(), by_size_.end(), [&](int a, int b) {
    if (nodes_[a].size() != nodes_[b].size()) return nodes_[a].size() > nodes_[b].size();
    return a < b;
  });
  removed_.assign(nodes_.size(), 0);
  next_.clear();
  int count = static_cast<int>(nodes_.size());
  for (int i : by_size_) {
    if (count >= wanted) break;
    count += Split(nodes_[i], &next_) - 1;
    removed_[i] = 1;
  }
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i) {
    if (!removed_[i]) next_.push_back(nodes_[i]);
  }
  nodes_.swap(next_);
}

void QuadtreeDistributor::SelectBest(int wanted, std::vector<Candidate>* selected) {
  best_.clear();
  for (const Node& node : nodes_) {
    int best = node.begin;
    for (int k = node.begin + 1; k < node.end; ++k) {
      if (Stronger(points_[k], points_[best])) best = k;
    }
    best_.push_back(best);
  }
  if (static_cast<int>(best_.size()) > wanted) {
    std::nth_element(best_.begin(), best_.begin() + wanted, best_.end(),
                     [&](int a, int b) { return Stronger(points_[a], points_[b]); });
    best_.resize(wanted);
  }
  selected->clear();
  for (int k : best_) selected->push_back(points_[k]);
  std::sort(selected->begin(), selected->end(), RowMajor);
}

void QuadtreeDistributor::Distribute(std::vector<Candidate>* candidates, float min_x, float max_x,
                                     float min_y, float max_y, int wanted,
                                     std::vector<Candidate>* selected) {
  MOSLAM_CHECK(max_x > min_x && max_y > min_y) << "empty distribution region";
  selected->clear();
  const int n = static_cast<int>(candidates->size());
  if (wanted <= 0 || n == 0) return;
  if (n <= wanted) {
    // Splitting would end with one candidate per node: every candidate is kept.
    selected->assign(candidates->begin(), candidates->end());
    std::sort(selected->begin(), selected->end(), RowMajor);
    return;
  }
  points_ = candidates->data();
  sorted_.resize(candidates->size());
  InitialNodes(min_x, max_x, min_y, max_y);
  while (static_cast<int>(nodes_.size()) < wanted) {
    int expandable = 0;
    for (const Node& node : nodes_) expandable += Expandable(node) ? 1 : 0;
    if (expandable == 0) break;
    // A full split adds up to 3 nodes per expandable node; if that could overshoot, split
    // selectively instead.
    if (static_cast<int>(nodes_.size()) + 3 * expandable <= wanted) {
      SplitAll();
    } else {
      SplitLargestUntil(wanted);
    }
  }
  SelectBest(wanted, selected);
  points_ = nullptr;
}

}  // namespace moslam::feature
