#include "moslam/feature/quadtree.h"

#include <algorithm>
#include <random>
#include <set>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

namespace moslam::feature {
namespace {

// Distinct integer positions (as FAST gives) with random responses in [0, 100).
std::vector<Candidate> RandomCandidates(int n, int width, int height, uint32_t seed) {
  std::mt19937 rng(seed);
  std::set<std::pair<int, int>> used;
  std::vector<Candidate> out;
  while (static_cast<int>(out.size()) < n) {
    const int x = static_cast<int>(rng() % width);
    const int y = static_cast<int>(rng() % height);
    if (!used.insert({x, y}).second) continue;
    out.push_back(
        {static_cast<float>(x), static_cast<float>(y), static_cast<float>(rng() % 10000) / 100.0f});
  }
  return out;
}

bool SamePoints(const std::vector<Candidate>& a, const std::vector<Candidate>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].x != b[i].x || a[i].y != b[i].y || a[i].response != b[i].response) return false;
  }
  return true;
}

TEST(Quadtree, KeepsEveryCandidateWhenThereAreFewerThanWanted) {
  std::vector<Candidate> candidates = RandomCandidates(50, 640, 480, 1);
  std::vector<Candidate> selected;
  QuadtreeDistributor distributor;
  distributor.Distribute(&candidates, 0, 640, 0, 480, 100, &selected);
  ASSERT_EQ(selected.size(), 50u);
  for (size_t i = 1; i < selected.size(); ++i) {
    EXPECT_TRUE(selected[i - 1].y < selected[i].y ||
                (selected[i - 1].y == selected[i].y && selected[i - 1].x < selected[i].x));
  }
}

TEST(Quadtree, ReturnsExactlyTheWantedNumberOfInputCandidates) {
  QuadtreeDistributor distributor;  // reused across calls on purpose
  for (const int wanted : {1, 7, 100, 333, 1000}) {
    std::vector<Candidate> candidates = RandomCandidates(3000, 1200, 350, wanted);
    const std::vector<Candidate> input = candidates;
    std::vector<Candidate> selected;
    distributor.Distribute(&candidates, 0, 1200, 0, 350, wanted, &selected);
    ASSERT_EQ(static_cast<int>(selected.size()), wanted);
    std::set<std::pair<float, float>> positions;
    for (const Candidate& c : input) positions.insert({c.x, c.y});
    std::set<std::pair<float, float>> chosen;
    for (const Candidate& c : selected) {
      EXPECT_TRUE(positions.count({c.x, c.y})) << "not an input candidate";
      chosen.insert({c.x, c.y});
    }
    EXPECT_EQ(chosen.size(), selected.size()) << "a candidate was selected twice";
  }
}

TEST(Quadtree, SpreadsKeypointsInsteadOfTakingTheStrongest) {
  // 2000 strong corners crowd the top-left 60x60 pixels; 500 weak ones cover the image. Keeping
  // the strongest would take only the crowd; the quadtree must reach most of the image.
  std::vector<Candidate> candidates = RandomCandidates(2000, 60, 60, 2);
  for (Candidate& c : candidates) c.response += 1000;
  for (Candidate c : RandomCandidates(500, 600, 600, 3)) {
    if (c.x < 60 && c.y < 60) continue;
    candidates.push_back(c);
  }
  std::vector<Candidate> selected;
  QuadtreeDistributor distributor;
  distributor.Distribute(&candidates, 0, 600, 0, 600, 200, &selected);
  ASSERT_EQ(selected.size(), 200u);
  std::set<int> cells;  // 6x6 grid of 100-pixel cells
  int in_crowd = 0;
  for (const Candidate& c : selected) {
    cells.insert(static_cast<int>(c.y / 100) * 6 + static_cast<int>(c.x / 100));
    if (c.x < 60 && c.y < 60) ++in_crowd;
  }
  EXPECT_GE(cells.size(), 34u);
  EXPECT_LT(in_crowd, 40);
  EXPECT_GT(in_crowd, 0);
}

TEST(Quadtree, KeepsTheStrongestCandidateOfEachNode) {
  // Four well separated clusters and four wanted: one keypoint per cluster, its strongest.
  std::vector<Candidate> candidates;
  const float centres[4][2] = {{100, 100}, {500, 100}, {100, 300}, {500, 300}};
  for (int k = 0; k < 4; ++k) {
    for (int i = 0; i < 10; ++i) {
      candidates.push_back(
          {centres[k][0] + i, centres[k][1] + (i % 3), static_cast<float>(10 * k + i)});
    }
  }
  std::vector<Candidate> selected;
  QuadtreeDistributor distributor;
  distributor.Distribute(&candidates, 0, 600, 0, 400, 4, &selected);
  ASSERT_EQ(selected.size(), 4u);
  std::vector<float> responses;
  for (const Candidate& c : selected) responses.push_back(c.response);
  std::sort(responses.begin(), responses.end());
  EXPECT_EQ(responses, (std::vector<float>{9, 19, 29, 39}));
}

TEST(Quadtree, ResultDoesNotDependOnInputOrder) {
  std::vector<Candidate> candidates = RandomCandidates(4000, 1226, 370, 4);
  // Equal responses must not make the result order-dependent either.
  for (size_t i = 0; i < candidates.size(); i += 3) candidates[i].response = 42;
  std::vector<Candidate> shuffled = candidates;
  std::shuffle(shuffled.begin(), shuffled.end(), std::mt19937(5));
  QuadtreeDistributor distributor;
  std::vector<Candidate> a, b;
  distributor.Distribute(&candidates, 0, 1226, 0, 370, 777, &a);
  distributor.Distribute(&shuffled, 0, 1226, 0, 370, 777, &b);
  EXPECT_TRUE(SamePoints(a, b));
}

TEST(Quadtree, HandlesEmptyInputAndZeroWanted) {
  std::vector<Candidate> none;
  std::vector<Candidate> selected = {{1, 2, 3}};
  QuadtreeDistributor distributor;
  distributor.Distribute(&none, 0, 10, 0, 10, 5, &selected);
  EXPECT_TRUE(selected.empty());
  std::vector<Candidate> some = RandomCandidates(10, 10, 10, 6);
  distributor.Distribute(&some, 0, 10, 0, 10, 0, &selected);
  EXPECT_TRUE(selected.empty());
}

}  // namespace
}  // namespace moslam::feature
