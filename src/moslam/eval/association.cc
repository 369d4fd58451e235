#include "moslam/eval/association.h"

#include <algorithm>
#include <cmath>
#include <tuple>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::eval {
namespace {

struct Candidate {
  double difference;
  double gt_stamp;
  double est_stamp;
  size_t gt;
  size_t est;
};

// Index in `stamps` (non-decreasing) of the first element whose shifted value reaches `value`.
size_t FirstShiftedAtLeast(const std::vector<double>& stamps, double shift, double value) {
  const auto it = std::partition_point(stamps.begin(), stamps.end(),
                                       [&](double s) { return s + shift < value; });
  return static_cast<size_t>(it - stamps.begin());
}

}  // namespace

std::vector<size_t> LastOfEachStamp(const std::vector<double>& stamps) {
  std::vector<size_t> keep;
  keep.reserve(stamps.size());
  for (size_t i = 0; i < stamps.size(); ++i) {
    if (i + 1 < stamps.size() && stamps[i + 1] == stamps[i]) continue;
    keep.push_back(i);
  }
  return keep;
}

Association AssociateGreedy(const std::vector<double>& gt_stamps,
                            const std::vector<double>& est_stamps, double offset, double max_dt) {
  const std::vector<size_t> gt_keys = LastOfEachStamp(gt_stamps);
  const std::vector<size_t> est_keys = LastOfEachStamp(est_stamps);
  std::vector<double> est_sorted;
  est_sorted.reserve(est_keys.size());
  for (const size_t e : est_keys) est_sorted.push_back(est_stamps[e]);

  // associate.py scans all pairs; only estimate stamps near each gt stamp can qualify, so a binary
  // search (with a margin for rounding; the exact test below decides) finds the same candidates.
  std::vector<Candidate> candidates;
  const double margin = max_dt + 1e-9 * (1.0 + std::abs(max_dt));
  for (const size_t g : gt_keys) {
    const double a = gt_stamps[g];
    for (size_t k = FirstShiftedAtLeast(est_sorted, offset, a - margin);
         k < est_sorted.size() && est_sorted[k] + offset <= a + margin; ++k) {
      const double b = est_sorted[k];
      const double difference = std::abs(a - (b + offset));
      if (difference < max_dt) candidates.push_back({difference, a, b, g, est_keys[k]});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.difference, x.gt_stamp, x.est_stamp) <
           std::tie(y.difference, y.gt_stamp, y.est_stamp);
  });

  std::vector<bool> gt_used(gt_stamps.size(), false);
  std::vector<bool> est_used(est_stamps.size(), false);
  std::vector<std::pair<size_t, size_t>> matches;
  for (const Candidate& c : candidates) {
    if (gt_used[c.gt] || est_used[c.est]) continue;
    gt_used[c.gt] = true;
    est_used[c.est] = true;
    matches.emplace_back(c.gt, c.est);
  }
  // Sorted by gt stamp; gt indices are in stamp order, and each is used once.
  std::sort(matches.begin(), matches.end());
  Association out;
  for (const auto& [g, e] : matches) {
    out.gt.push_back(g);
    out.est.push_back(e);
  }
  return out;
}

Association AssociateNearest(const std::vector<double>& gt_stamps,
                             const std::vector<double>& est_stamps, double offset, double max_dt) {
  // evo: the offset moves the second trajectory (the estimate); when the gt is the longer one,
  // the gt is shifted by -offset instead, exactly as sync.associate_trajectories does.
  const bool est_longer = est_stamps.size() > gt_stamps.size();
  const std::vector<double>& shorter = est_longer ? gt_stamps : est_stamps;
  const std::vector<double>& longer = est_longer ? est_stamps : gt_stamps;
  const double shift = est_longer ? offset : -offset;

  Association out;
  if (longer.empty()) return out;
  for (size_t i = 0; i < shorter.size(); ++i) {
    const double s = shorter[i];
    // Shifted stamps stay non-decreasing, so the nearest is at the boundary of those below s.
    const size_t k = FirstShiftedAtLeast(longer, shift, s);
    size_t best = 0;
    double best_difference = 0;
    bool found = false;
    auto consider = [&](size_t j) {
      const double d = std::abs((longer[j] + shift) - s);
      if (!found || d < best_difference) {
        best = j;
        best_difference = d;
        found = true;
      }
    };
    if (k > 0) {
      // The first occurrence of the value just below s, as argmin would return it.
      consider(FirstShiftedAtLeast(longer, shift, longer[k - 1] + shift));
    }
    if (k < longer.size()) consider(k);
    MOSLAM_CHECK(found);
    if (best_difference <= max_dt) {
      out.gt.push_back(est_longer ? i : best);
      out.est.push_back(est_longer ? best : i);
    }
  }
  return out;
}

Association AssociateByIndex(size_t gt_count, size_t est_count) {
  if (gt_count != est_count) {
    ThrowInput(
        "trajectories without timestamps are matched by index and need equal lengths, but the "
        "ground truth has {} poses and the estimate {} (give the ground truth timestamps with "
        "--gt-times to match by time)",
        gt_count, est_count);
  }
  Association out;
  for (size_t i = 0; i < gt_count; ++i) {
    out.gt.push_back(i);
    out.est.push_back(i);
  }
  return out;
}

}  // namespace moslam::eval
