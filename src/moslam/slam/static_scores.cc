// Static probabilities of map points from their residuals (static_scores.h).
#include "moslam/slam/static_scores.h"

#include <algorithm>
#include <cmath>

#include "moslam/util/error.h"

namespace moslam::slam {
namespace {

double LogOdds(double p) { return std::log(p / (1.0 - p)); }
double FromLogOdds(double l) { return 1.0 / (1.0 + std::exp(-l)); }

}  // namespace

void StaticScoreOptions::Check() const {
  if (!(prior > 0.0 && prior < 1.0)) {
    ThrowInput("StaticScoreOptions.prior must be in (0, 1) (got {})", prior);
  }
  if (!(max_step > 0.0)) ThrowInput("StaticScoreOptions.max_step must be > 0 (got {})", max_step);
  if (!(max_log_odds > 0.0)) {
    ThrowInput("StaticScoreOptions.max_log_odds must be > 0 (got {})", max_log_odds);
  }
  if (!(cull_probability > 0.0 && cull_probability < 0.5)) {
    ThrowInput("StaticScoreOptions.cull_probability must be in (0, 0.5) (got {})",
               cull_probability);
  }
  if (min_judged < 1) ThrowInput("StaticScoreOptions.min_judged must be >= 1 (got {})", min_judged);
  if (!(min_weight > 0.0 && min_weight <= 1.0)) {
    ThrowInput("StaticScoreOptions.min_weight must be in (0, 1] (got {})", min_weight);
  }
  // A cull probability under the floor of the clamp could never be reached.
  if (cull_probability <= FromLogOdds(-max_log_odds)) {
    ThrowInput(
        "StaticScoreOptions.cull_probability ({}) must be above the clamp's floor {} "
        "(1 / (1 + exp(max_log_odds)))",
        cull_probability, FromLogOdds(-max_log_odds));
  }
}

StaticScores::StaticScores(const StaticScoreOptions& options) : options_(options) {
  options_.Check();
  prior_log_odds_ =
      std::clamp(LogOdds(options_.prior), -options_.max_log_odds, options_.max_log_odds);
}

double StaticScores::Probability(uint64_t point_id) const {
  const auto it = entries_.find(point_id);
  return FromLogOdds(it == entries_.end() ? prior_log_odds_ : it->second.log_odds);
}

double StaticScores::Weight(uint64_t point_id) const {
  if (!options_.enabled) return 1.0;
  // Full weight while static is at least as likely as moving: a static scene, where no point
  // has been an outlier for several frames running, is optimized exactly as without scores.
  return std::clamp(2.0 * Probability(point_id), options_.min_weight, 1.0);
}

StaticScores::Entry& StaticScores::EntryFor(const std::shared_ptr<map::MapPoint>& point) {
  auto [it, inserted] = entries_.try_emplace(point->id);
  if (inserted) {
    it->second.log_odds = prior_log_odds_;
    it->second.point = point;
  }
  return it->second;
}

void StaticScores::Seen(const std::shared_ptr<map::MapPoint>& point, double timestamp) {
  Entry& e = EntryFor(point);
  if (!e.seen) {
    e.seen = true;
    e.first_seen = timestamp;
  }
}

double StaticScores::Age(uint64_t point_id, double timestamp) const {
  const auto it = entries_.find(point_id);
  if (it == entries_.end() || !it->second.seen) return 0.0;
  return std::max(0.0, timestamp - it->second.first_seen);
}

double StaticScores::Observe(const std::shared_ptr<map::MapPoint>& point, double chi2,
                             double threshold) {
  Entry& e = EntryFor(point);
  // log N(chi2) - log(flat) = (threshold - chi2) / 2: zero at the threshold.
  const double step = std::clamp(0.5 * (threshold - chi2), -options_.max_step, options_.max_step);
  e.log_odds = std::clamp(e.log_odds + step, -options_.max_log_odds, options_.max_log_odds);
  ++e.judged;
  return FromLogOdds(e.log_odds);
}

bool StaticScores::ShouldCull(uint64_t point_id) const {
  if (!options_.enabled) return false;
  const auto it = entries_.find(point_id);
  return it != entries_.end() && it->second.judged >= options_.min_judged &&
         FromLogOdds(it->second.log_odds) < options_.cull_probability;
}

size_t StaticScores::Prune() {
  size_t removed = 0;
  for (auto it = entries_.begin(); it != entries_.end();) {
    const std::shared_ptr<map::MapPoint> p = it->second.point.lock();
    if (!p || p->bad) {
      it = entries_.erase(it);
      ++removed;
    } else {
      ++it;
    }
  }
  return removed;
}

}  // namespace moslam::slam
