// Matching the poses of an estimate to those of the ground truth.
//
// Stamps are seconds; `offset` is added to the estimate's stamps before comparing (both TUM's
// associate.py and evo add it to the second trajectory, the estimate).
#pragma once

#include <cstddef>
#include <vector>

namespace moslam::eval {

// Index pairs (gt[k], est[k]) of matched poses.
struct Association {
  std::vector<size_t> gt;
  std::vector<size_t> est;
  size_t size() const { return gt.size(); }
};

// TUM associate.py (used by evaluate_ate.py): every pair with |a - (b + offset)| < max_dt is a
// candidate; candidates are taken greedily by increasing difference (ties by gt stamp, then est
// stamp), each stamp at most once. The result is sorted by gt stamp. A stamp that repeats counts
// once, as its later pose (the scripts read files into a dict). Stamps must be non-decreasing.
Association AssociateGreedy(const std::vector<double>& gt_stamps,
                            const std::vector<double>& est_stamps, double offset, double max_dt);

// evo's sync.associate_trajectories: for each stamp of the shorter trajectory (the estimate when
// both are equally long), the nearest stamp of the longer one, kept when the difference is
// <= max_dt. The first of equally near stamps wins (numpy.argmin); a stamp of the longer
// trajectory may be used more than once. Ordered by the shorter trajectory. Stamps must be
// non-decreasing (trajectory_io.h guarantees it).
Association AssociateNearest(const std::vector<double>& gt_stamps,
                             const std::vector<double>& est_stamps, double offset, double max_dt);

// Indices of the last pose of each distinct stamp of a non-decreasing list: the poses TUM's
// scripts see, as they read files into a dict keyed by stamp.
std::vector<size_t> LastOfEachStamp(const std::vector<double>& stamps);

// Pose i with pose i, for two trajectories without timestamps (KITTI). The counts must be equal
// (InputError naming both otherwise).
Association AssociateByIndex(size_t gt_count, size_t est_count);

}  // namespace moslam::eval
