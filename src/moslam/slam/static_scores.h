// A static probability per map point from its residuals across frames (issue 24, "geometry for
// what no network knows"; the per-keypoint static probability of CFP-SLAM, Hu et al. 2022, which
// weights pose optimization with it). Each tracked frame's final pose-only optimization gives
// every matched point a whitened squared error chi2. A static point's chi2 follows a chi-square
// law; a point on something that moves has an error that knows no bound. The log-odds of
// "static" take the log of the ratio of a Gaussian likelihood, exp(-chi2 / 2), and a flat one
// that equals it at the chi-square threshold: (threshold - chi2) / 2 per frame, clamped so one
// frame is never decisive. The probability then
//  - weights the point's residual in the next frames' pose optimizations (a point that has been
//    moving pulls the camera less, even when it is matched again within the outlier threshold,
//    e.g. as an object slows down);
//  - erases the point from the map once it has been judged moving often enough (min_judged
//    frames and a probability under cull_probability): ORB-SLAM2 would keep it, flag it an
//    outlier frame after frame, and match it again when the object stops somewhere else.
// Points never matched keep their prior. The time each point was first matched is kept too: how
// long a point has been known is its vote in optim/pose_consensus.h. State lives here, keyed by the
// point's id, not on MapPoint (house rule: an algorithm's scratch state is its own); entries of
// erased points are pruned as they are found bad.
//
// Not thread-safe: one instance per tracker, used under Map::mutex() like the tracker's state.
#pragma once

#include <cstdint>
#include <memory>
#include <unordered_map>

#include "moslam/map/map_point.h"

namespace moslam::slam {

struct StaticScoreOptions {
  bool enabled = true;
  double prior = 0.9;              // static probability of a point never judged, (0, 1)
  double max_step = 2.0;           // largest change of the log-odds by one frame (> 0)
  double max_log_odds = 4.0;       // clamp (p = 0.982): a long-static point can still turn
  double cull_probability = 0.05;  // erase below this probability ... (0, 0.5)
  int min_judged = 3;              // ... after at least this many judged frames (>= 1)
  double min_weight = 0.05;        // weight floor in pose optimization, (0, 1]
  void Check() const;              // InputError naming the field
};

class StaticScores {
 public:
  explicit StaticScores(const StaticScoreOptions& options = {});

  // Static probability of the point: the prior when never judged.
  double Probability(uint64_t point_id) const;
  // Its weight in pose optimization: 1 while the probability is >= 0.5, below that twice the
  // probability, at least min_weight; 1 when disabled.
  double Weight(uint64_t point_id) const;
  // One frame's evidence: the point was matched with whitened squared error `chi2` against the
  // chi-square `threshold` of its observation (2 or 3 DoF). Returns the new probability.
  double Observe(const std::shared_ptr<map::MapPoint>& point, double chi2, double threshold);
  // The tracker matched the point at `timestamp` (seconds): the first call is its first sight.
  void Seen(const std::shared_ptr<map::MapPoint>& point, double timestamp);
  // Seconds since the point's first sight (0 when never seen).
  double Age(uint64_t point_id, double timestamp) const;
  // The point has been judged moving often enough to be erased.
  bool ShouldCull(uint64_t point_id) const;
  // Drops entries whose points are gone (erased or bad); returns how many.
  size_t Prune();
  size_t size() const { return entries_.size(); }
  const StaticScoreOptions& options() const { return options_; }

 private:
  struct Entry {
    double log_odds = 0.0;
    int judged = 0;
    double first_seen = 0.0;
    bool seen = false;
    std::weak_ptr<map::MapPoint> point;
  };
  Entry& EntryFor(const std::shared_ptr<map::MapPoint>& point);
  StaticScoreOptions options_;
  double prior_log_odds_ = 0.0;
  std::unordered_map<uint64_t, Entry> entries_;
};

}  // namespace moslam::slam
