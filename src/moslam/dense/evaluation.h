// Scores of a dense map against the synthetic generator's ground truth (issue 27): how much of
// the map lies where people were, and how much of the static scene it holds. Voxels are compared
// at the fusion's resolution, on OctoMap's grid (a point p lies in the voxel floor(p /
// resolution)).
#pragma once

#include <cstddef>
#include <cstdint>
#include <unordered_set>
#include <vector>

#include <Eigen/Core>

#include "moslam/dense/fusion.h"

namespace moslam::dense {

class VoxelSet {
 public:
  explicit VoxelSet(double resolution);
  void Add(const Eigen::Vector3d& p);
  void Add(const std::vector<Eigen::Vector3d>& points);
  bool Contains(const Eigen::Vector3d& p) const;
  // p's voxel or any of its 26 neighbours.
  bool ContainsNear(const Eigen::Vector3d& p) const;
  size_t size() const { return keys_.size(); }
  double resolution() const { return resolution_; }
  // Centres of the voxels, in no particular order.
  std::vector<Eigen::Vector3d> Centres() const;

 private:
  using Key = uint64_t;  // three 21-bit signed cell indices packed (+-1e6 cells: 50 km at 5 cm)
  Key KeyOf(const Eigen::Vector3d& p) const;
  Key KeyOf(int64_t x, int64_t y, int64_t z) const;
  double resolution_;
  std::unordered_set<Key> keys_;
};

struct DenseMapScores {
  size_t occupied = 0;           // voxels of the map
  size_t in_people = 0;          // of them inside the people's voxels (at any time) and not static
  double people_fraction = 0.0;  // in_people / occupied
  size_t static_seen = 0;        // voxels of the static scene the keyframes saw
  size_t static_occupied = 0;    // of them occupied in the map
  size_t static_occupied_near = 0;  // ... or with an occupied neighbour (one voxel of tolerance)
  double completeness = 0.0;        // static_occupied / static_seen
  double completeness_near = 0.0;   // static_occupied_near / static_seen
};

// `people`: the voxels the people occupied at any time (ground-truth masks and depth at the
// ground-truth poses of every frame); `statics`: the static scene's voxels seen by the keyframes.
// A voxel in both (a foot on the floor) counts as static. The map's voxels must be in the ground
// truth's frame.
DenseMapScores ScoreDenseMap(const std::vector<Voxel>& occupied, const VoxelSet& people,
                             const VoxelSet& statics);

}  // namespace moslam::dense
