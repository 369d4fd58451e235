#include "moslam/eval/rpe.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <spdlog/spdlog.h>

#include "moslam/util/check.h"
#include "moslam/util/error.h"
#include "moslam/util/strings.h"

namespace moslam::eval {
namespace {

using PairList = std::vector<std::pair<size_t, size_t>>;

constexpr double kDegreesPerRadian = 180.0 / M_PI;

// ----- Seeded subsampling (replaces Python's random in evaluate_rpe.py) -----

// A uniform index below n from raw generator output; the modulo bias is below 2^-40 for any
// trajectory size, and unlike std::uniform_int_distribution the result is the same on every
// standard library.
size_t RandomIndex(std::mt19937_64& rng, size_t n) { return static_cast<size_t>(rng() % n); }

// random.sample: max_pairs distinct pairs, kept in their original order.
PairList SampleWithoutReplacement(const PairList& pairs, size_t count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<size_t> order(pairs.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  for (size_t i = 0; i < count; ++i)
    std::swap(order[i], order[i + RandomIndex(rng, order.size() - i)]);
  order.resize(count);
  std::sort(order.begin(), order.end());
  PairList out;
  for (const size_t k : order) out.push_back(pairs[k]);
  return out;
}

// ----- TUM evaluate_rpe.py -----

// The "index" along which delta is measured (evaluate_rpe.py: index_est).
std::vector<double> TumIndex(const std::vector<double>& stamps,
                             const std::vector<Eigen::Matrix4d>& poses, DeltaUnit unit) {
  const size_t n = poses.size();
  std::vector<double> index;
  index.reserve(n);
  if (unit == DeltaUnit::kSeconds) return stamps;
  if (unit == DeltaUnit::kFrames) {
    for (size_t i = 0; i < n; ++i) index.push_back(static_cast<double>(i));
    return index;
  }
  // distances_along_trajectory / rotations_along_trajectory: sums over ominus(P_k+1, P_k).
  index.push_back(0.0);
  double sum = 0;
  for (size_t k = 0; k + 1 < n; ++k) {
    const Eigen::Matrix4d motion = poses[k + 1].inverse() * poses[k];
    if (unit == DeltaUnit::kMetres) {
      sum += motion.topRightCorner<3, 1>().norm();
    } else {
      const double scale = unit == DeltaUnit::kDegrees ? kDegreesPerRadian : 1.0;
      sum += RotationAngleOfMatrix(motion.topLeftCorner<3, 3>()) * scale;
    }
    index.push_back(sum);
  }
  return index;
}

PairList TumPairs(const std::vector<double>& index, const RpeOptions& options) {
  const size_t n = index.size();
  PairList pairs;
  if (options.all_pairs) {
    if (options.max_pairs == 0 ||
        static_cast<double>(n) < std::sqrt(static_cast<double>(options.max_pairs))) {
      for (size_t i = 0; i < n; ++i) {
        for (size_t j = 0; j < n; ++j) pairs.emplace_back(i, j);
      }
      return pairs;
    }
    std::mt19937_64 rng(options.seed);
    for (size_t k = 0; k < options.max_pairs; ++k) {
      const size_t i = RandomIndex(rng, n);
      pairs.emplace_back(i, RandomIndex(rng, n));
    }
    return pairs;
  }
  for (size_t i = 0; i < n; ++i) {
    const size_t j = FindClosestIndex(index, index[i] + options.delta);
    if (j != n - 1) pairs.emplace_back(i, j);
  }
  if (options.max_pairs != 0 && pairs.size() > options.max_pairs) {
    spdlog::warn(
        "{} RPE pairs; a seeded random {} of them are compared, as evaluate_rpe.py "
        "samples (max_pairs 0 compares all)",
        pairs.size(), options.max_pairs);
    pairs = SampleWithoutReplacement(pairs, options.max_pairs, options.seed);
  }
  return pairs;
}

void ComputeTum(const Trajectory& gt, const Trajectory& est, RpeResult* result) {
  const RpeOptions& options = result->options;
  // The scripts' dicts: one pose per distinct stamp (indices as stamps for KITTI files).
  auto distinct = [](const Trajectory& t, std::vector<size_t>* keys, std::vector<double>* stamps,
                     std::vector<Eigen::Matrix4d>* poses) {
    std::vector<double> all(t.size());
    for (size_t i = 0; i < t.size(); ++i) all[i] = t.TimeOrIndex(i);
    *keys = LastOfEachStamp(all);
    for (const size_t k : *keys) {
      stamps->push_back(all[k]);
      poses->push_back(t.Matrix(k));
    }
  };
  std::vector<size_t> gt_keys, est_keys;
  std::vector<double> gt_stamps, est_stamps;
  std::vector<Eigen::Matrix4d> gt_poses, est_poses;
  distinct(gt, &gt_keys, &gt_stamps, &gt_poses);
  distinct(est, &est_keys, &est_stamps, &est_poses);
  if (gt_stamps.size() < 2 || est_stamps.size() < 2) {
    ThrowInput("RPE needs at least 2 poses in '{}' and '{}'", gt.name, est.name);
  }

  const PairList pairs = TumPairs(TumIndex(est_stamps, est_poses, options.delta_unit), options);
  std::vector<double> intervals;
  for (size_t k = 0; k + 1 < gt_stamps.size(); ++k) {
    intervals.push_back(gt_stamps[k + 1] - gt_stamps[k]);
  }
  const double max_time_difference = 2 * Median(intervals);

  std::vector<double> translation, rotation;
  for (const auto& [i, j] : pairs) {
    const double e0 = est_stamps[i] + options.offset;
    const double e1 = est_stamps[j] + options.offset;
    const size_t g0 = FindClosestIndex(gt_stamps, e0);
    const size_t g1 = FindClosestIndex(gt_stamps, e1);
    if (std::abs(gt_stamps[g0] - e0) > max_time_difference ||
        std::abs(gt_stamps[g1] - e1) > max_time_difference) {
      continue;
    }
    const Eigen::Matrix4d est_motion = est_poses[j].inverse() * est_poses[i];
    const Eigen::Matrix4d gt_motion = gt_poses[g1].inverse() * gt_poses[g0];
    const Eigen::Matrix4d E = est_motion.inverse() * gt_motion;
    translation.push_back(E.topRightCorner<3, 1>().norm());
    rotation.push_back(RotationAngleOfMatrix(E.topLeftCorner<3, 3>()) * kDegreesPerRadian);
    result->pairs.emplace_back(est_keys[i], est_keys[j]);
    result->pair_times.push_back(est_stamps[i]);
  }
  if (translation.size() < 2) {
    ThrowInput("couldn't find matching timestamp pairs between '{}' and '{}' for the RPE", gt.name,
               est.name);
  }
  result->translation = MakeSeries(std::move(translation));
  result->rotation = MakeSeries(std::move(rotation));
}

// ----- evo_rpe (evo.core.filters / metrics.RPE) -----

PairList EvoFramePairs(size_t n, size_t delta, bool all_pairs) {
  PairList pairs;
  if (all_pairs) {
    for (size_t i = 0; i + delta < n; ++i) pairs.emplace_back(i, i + delta);
    return pairs;
  }
  for (size_t i = 0; i + delta < n; i += delta) pairs.emplace_back(i, i + delta);
  return pairs;
}

PairList ConsecutiveIds(const std::vector<size_t>& ids) {
  PairList pairs;
  for (size_t k = 0; k + 1 < ids.size(); ++k) pairs.emplace_back(ids[k], ids[k + 1]);
  return pairs;
}

PairList EvoPathPairs(const Trajectory& est, double delta, double tolerance, bool all_pairs) {
  const size_t n = est.size();
  if (!all_pairs) {
    std::vector<size_t> ids;
    double path = 0;
    for (size_t i = 0; i < n; ++i) {
      if (i > 0) path += (est.Position(i) - est.Position(i - 1)).norm();
      if (path >= delta) {
        ids.push_back(i);
        path = 0;
      }
    }
    return ConsecutiveIds(ids);
  }
  std::vector<double> distance(n, 0.0);  // geometry.accumulated_distances
  for (size_t i = 1; i < n; ++i) {
    distance[i] = distance[i - 1] + (est.Position(i - 1) - est.Position(i)).norm();
  }
  PairList pairs;
  for (size_t i = 0; i + 1 < n; ++i) {
    size_t best = i + 1;
    double best_residual = std::abs(distance[i + 1] - distance[i] - delta);
    for (size_t j = i + 2; j < n; ++j) {
      const double residual = std::abs(distance[j] - distance[i] - delta);
      if (residual < best_residual) {
        best = j;
        best_residual = residual;
      }
    }
    if (best_residual <= tolerance) pairs.emplace_back(i, best);
  }
  return pairs;
}

double AngleBetween(const Trajectory& t, size_t a, size_t b, double scale) {
  const Eigen::Matrix3d Ra = t.Matrix(a).topLeftCorner<3, 3>();
  const Eigen::Matrix3d Rb = t.Matrix(b).topLeftCorner<3, 3>();
  return RotationAngleOfMatrix(Ra.transpose() * Rb) * scale;
}

PairList EvoAnglePairs(const Trajectory& est, double delta, double tolerance, double scale,
                       bool all_pairs) {
  const size_t n = est.size();
  PairList pairs;
  if (!all_pairs) {
    double accumulated = 0;
    size_t start = 0;
    for (size_t i = 0; i + 1 < n; ++i) {
      accumulated += AngleBetween(est, i, i + 1, scale);
      if (accumulated >= delta) {
        pairs.emplace_back(start, i + 1);
        accumulated = 0;
        start = i + 1;
      }
    }
    return pairs;
  }
  for (size_t i = 0; i + 1 < n; ++i) {
    for (size_t j = i + 1; j < n; ++j) {
      const double angle = AngleBetween(est, i, j, scale);
      if (delta - tolerance <= angle && angle <= delta + tolerance) pairs.emplace_back(i, j);
    }
  }
  return pairs;
}

PairList EvoPairs(const Trajectory& est, const RpeOptions& options) {
  const double tolerance = options.delta * options.all_pairs_tolerance;
  switch (options.delta_unit) {
    case DeltaUnit::kFrames:
      return EvoFramePairs(est.size(), static_cast<size_t>(options.delta), options.all_pairs);
    case DeltaUnit::kMetres:
      return EvoPathPairs(est, options.delta, tolerance, options.all_pairs);
    case DeltaUnit::kRadians:
      return EvoAnglePairs(est, options.delta, tolerance, 1.0, options.all_pairs);
    case DeltaUnit::kDegrees:
      return EvoAnglePairs(est, options.delta, tolerance, kDegreesPerRadian, options.all_pairs);
    case DeltaUnit::kSeconds:
      break;
  }
  MOSLAM_CHECK(false) << "unit checked in RpeOptions::Check";
  return {};
}

void ComputeEvo(const Trajectory& gt, const Trajectory& est, RpeResult* result) {
  const RpeOptions& options = result->options;
  const Association association =
      AssociatePoses(gt, est, Convention::kEvo, options.max_dt, options.offset);
  if (association.size() < 2) {
    ThrowInput("RPE needs at least 2 associated poses between '{}' and '{}', found {}", gt.name,
               est.name, association.size());
  }
  const Trajectory Q = gt.Subset(association.gt);
  Trajectory P = est.Subset(association.est);
  result->alignment = EstimateAlignment(Q, P, options.alignment, AlignmentSolver::kUmeyama);
  P.Transform(result->alignment);

  const PairList pairs = EvoPairs(P, options);
  if (pairs.empty()) {
    ThrowInput("delta {} {} gives no pose pair on '{}' ({} associated poses)", options.delta,
               DeltaUnitName(options.delta_unit), est.name, P.size());
  }
  std::vector<double> translation, rotation;
  for (const auto& [i, j] : pairs) {
    const Eigen::Matrix4d Q_rel = InverseAsEvo(Q.Matrix(i)) * Q.Matrix(j);
    const Eigen::Matrix4d P_rel = InverseAsEvo(P.Matrix(i)) * P.Matrix(j);
    const Eigen::Matrix4d E = InverseAsEvo(Q_rel) * P_rel;
    translation.push_back(E.topRightCorner<3, 1>().norm());
    rotation.push_back(RotationAngleOfMatrix(E.topLeftCorner<3, 3>()) * kDegreesPerRadian);
    result->pairs.emplace_back(association.est[i], association.est[j]);
    result->pair_times.push_back(P.TimeOrIndex(i));
  }
  result->translation = MakeSeries(std::move(translation));
  result->rotation = MakeSeries(std::move(rotation));
  result->poses = MakeComparedPoses(Q, P);
}

// For the tum convention: the estimate aligned as requested (via evaluate_ate.py's association),
// and the associated positions for plots.
Trajectory AlignForTum(const Trajectory& gt, const Trajectory& est, RpeResult* result) {
  const RpeOptions& options = result->options;
  const Association association =
      AssociatePoses(gt, est, Convention::kTum, options.max_dt, options.offset);
  Trajectory aligned = est;
  const Trajectory matched_gt = gt.Subset(association.gt);
  if (options.alignment != AlignmentMode::kNone) {
    result->alignment = EstimateAlignment(matched_gt, est.Subset(association.est),
                                          options.alignment, AlignmentSolver::kHorn);
    aligned.Transform(result->alignment);
  }
  result->poses = MakeComparedPoses(matched_gt, aligned.Subset(association.est));
  return aligned;
}

}  // namespace

DeltaUnit ParseDeltaUnit(const std::string& name) {
  const std::string lower = ToLower(name);
  if (lower == "f") return DeltaUnit::kFrames;
  if (lower == "s") return DeltaUnit::kSeconds;
  if (lower == "m") return DeltaUnit::kMetres;
  if (lower == "rad") return DeltaUnit::kRadians;
  if (lower == "deg") return DeltaUnit::kDegrees;
  ThrowInput("unknown delta unit '{}' (f, s, m, rad, deg)", name);
}

const char* DeltaUnitName(DeltaUnit unit) {
  switch (unit) {
    case DeltaUnit::kFrames:
      return "f";
    case DeltaUnit::kSeconds:
      return "s";
    case DeltaUnit::kMetres:
      return "m";
    case DeltaUnit::kRadians:
      return "rad";
    case DeltaUnit::kDegrees:
      return "deg";
  }
  return "?";
}

void RpeOptions::Check() const {
  if (!(max_dt > 0) || !std::isfinite(max_dt)) {
    ThrowInput("max_dt must be a positive number of seconds, got {}", max_dt);
  }
  if (!std::isfinite(offset)) ThrowInput("offset must be finite, got {}", offset);
  if (!(delta > 0) || !std::isfinite(delta)) ThrowInput("delta must be positive, got {}", delta);
  if (delta_unit == DeltaUnit::kFrames && delta != std::floor(delta)) {
    ThrowInput("delta must be a whole number of frames, got {}", delta);
  }
  if (convention == Convention::kEvo && delta_unit == DeltaUnit::kSeconds) {
    ThrowInput("the evo convention has no delta unit 's' (evo_rpe: f, m, rad, deg)");
  }
  if (!(all_pairs_tolerance >= 0) || !std::isfinite(all_pairs_tolerance)) {
    ThrowInput("all-pairs tolerance must be >= 0, got {}", all_pairs_tolerance);
  }
}

RpeOptions RpeOptions::Defaults(Convention convention) {
  RpeOptions options;
  options.convention = convention;
  options.max_dt = DefaultMaxDt(convention);
  options.delta_unit = convention == Convention::kTum ? DeltaUnit::kSeconds : DeltaUnit::kFrames;
  return options;
}

size_t FindClosestIndex(const std::vector<double>& values, double target) {
  MOSLAM_CHECK(!values.empty());
  // Transcribed rule for rule from evaluate_rpe.py so that ties resolve as in the script.
  size_t begin = 0;
  size_t end = values.size();
  double difference = std::abs(values[0] - target);
  size_t best = 0;
  while (begin < end) {
    const size_t middle = (begin + end) / 2;
    if (std::abs(values[middle] - target) < difference) {
      difference = std::abs(values[middle] - target);
      best = middle;
    }
    if (target == values[middle]) return middle;
    if (values[middle] > target) {
      end = middle;
    } else {
      begin = middle + 1;
    }
  }
  return best;
}

RpeResult ComputeRpe(const Trajectory& gt, const Trajectory& est, const RpeOptions& options) {
  options.Check();
  RpeResult result;
  result.options = options;
  RequireComparableStamps(gt, est);
  if (options.convention == Convention::kEvo) {
    ComputeEvo(gt, est, &result);
  } else {
    ComputeTum(gt, AlignForTum(gt, est, &result), &result);
  }
  return result;
}

}  // namespace moslam::eval
