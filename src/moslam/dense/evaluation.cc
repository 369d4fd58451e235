#include "moslam/dense/evaluation.h"

#include <cmath>

#include "moslam/util/check.h"

namespace moslam::dense {

namespace {
constexpr int64_t kBias = int64_t{1} << 20;  // cell indices -2^20 .. 2^20-1
constexpr uint64_t kMask = (uint64_t{1} << 21) - 1;
}  // namespace

VoxelSet::VoxelSet(double resolution) : resolution_(resolution) { MOSLAM_CHECK(resolution > 0.0); }

VoxelSet::Key VoxelSet::KeyOf(int64_t x, int64_t y, int64_t z) const {
  return ((static_cast<uint64_t>(x + kBias) & kMask) << 42) |
         ((static_cast<uint64_t>(y + kBias) & kMask) << 21) |
         (static_cast<uint64_t>(z + kBias) & kMask);
}

VoxelSet::Key VoxelSet::KeyOf(const Eigen::Vector3d& p) const {
  return KeyOf(static_cast<int64_t>(std::floor(p.x() / resolution_)),
               static_cast<int64_t>(std::floor(p.y() / resolution_)),
               static_cast<int64_t>(std::floor(p.z() / resolution_)));
}

void VoxelSet::Add(const Eigen::Vector3d& p) { keys_.insert(KeyOf(p)); }

void VoxelSet::Add(const std::vector<Eigen::Vector3d>& points) {
  for (const Eigen::Vector3d& p : points) Add(p);
}

bool VoxelSet::Contains(const Eigen::Vector3d& p) const { return keys_.count(KeyOf(p)) > 0; }

bool VoxelSet::ContainsNear(const Eigen::Vector3d& p) const {
  const auto x = static_cast<int64_t>(std::floor(p.x() / resolution_));
  const auto y = static_cast<int64_t>(std::floor(p.y() / resolution_));
  const auto z = static_cast<int64_t>(std::floor(p.z() / resolution_));
  for (int64_t dx = -1; dx <= 1; ++dx) {
    for (int64_t dy = -1; dy <= 1; ++dy) {
      for (int64_t dz = -1; dz <= 1; ++dz) {
        if (keys_.count(KeyOf(x + dx, y + dy, z + dz)) > 0) return true;
      }
    }
  }
  return false;
}

std::vector<Eigen::Vector3d> VoxelSet::Centres() const {
  std::vector<Eigen::Vector3d> centres;
  centres.reserve(keys_.size());
  for (const Key key : keys_) {
    const auto cell = [&](int shift) {
      return static_cast<double>(static_cast<int64_t>((key >> shift) & kMask) - kBias);
    };
    centres.emplace_back((cell(42) + 0.5) * resolution_, (cell(21) + 0.5) * resolution_,
                         (cell(0) + 0.5) * resolution_);
  }
  return centres;
}

DenseMapScores ScoreDenseMap(const std::vector<Voxel>& occupied, const VoxelSet& people,
                             const VoxelSet& statics) {
  MOSLAM_CHECK(people.resolution() == statics.resolution());
  DenseMapScores s;
  s.occupied = occupied.size();
  VoxelSet map(statics.resolution());
  for (const Voxel& v : occupied) {
    const Eigen::Vector3d c = v.centre.cast<double>();
    map.Add(c);
    if (people.Contains(c) && !statics.Contains(c)) ++s.in_people;
  }
  for (const Eigen::Vector3d& c : statics.Centres()) {
    ++s.static_seen;
    if (map.Contains(c)) ++s.static_occupied;
    if (map.ContainsNear(c)) ++s.static_occupied_near;
  }
  if (s.occupied > 0) s.people_fraction = static_cast<double>(s.in_people) / s.occupied;
  if (s.static_seen > 0) {
    s.completeness = static_cast<double>(s.static_occupied) / s.static_seen;
    s.completeness_near = static_cast<double>(s.static_occupied_near) / s.static_seen;
  }
  return s;
}

}  // namespace moslam::dense
