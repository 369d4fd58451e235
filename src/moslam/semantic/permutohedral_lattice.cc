#include "moslam/semantic/permutohedral_lattice.h"

#include <algorithm>
#include <bitset>
#include <cmath>
#include <cstring>
#include <functional>
#include <utility>

#include "moslam/semantic/crf_simd.h"
#include "moslam/semantic/thread_pool.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

// Lattice coordinates are packed as 21-bit fields, three to a 64-bit word; kBias makes them
// non-negative and kMaxCoordinate leaves room for the simplex and neighbour offsets.
constexpr int kFieldBits = 21;
constexpr int64_t kBias = int64_t{1} << (kFieldBits - 1);
constexpr float kMaxCoordinate = static_cast<float>(kBias - 64);

// One point's place in the lattice: its elevated position, the nearest remainder-0 lattice point
// rem0, the ordering (rank 0 = largest) of elevated - rem0, and the barycentric weights of the
// d + 1 simplex vertices (vertex k = rem0 + the k-th canonical offset, see VertexCoordinate).
template <int D>
struct Embedding {
  float elevated[D + 1];
  int rem0[D + 1];
  int rank[D + 1];
  float barycentric[D + 2];
};

// Scale of feature i before elevation: the elevation below maps R^d onto the hyperplane
// sum(x) = 0 with orthogonal columns of norm sqrt((i + 1)(i + 2)); dividing by that norm makes it
// an isometry, and the factor (d + 1) sqrt(2/3) sets the lattice spacing so that the [1/2 1 1/2]
// blurs give a Gaussian of unit standard deviation (Adams et al. 2010, section 3.1).
void FeatureScales(int dim, float* scale) {
  const double spacing = (dim + 1) * std::sqrt(2.0 / 3.0);
  for (int i = 0; i < dim; ++i) {
    scale[i] = static_cast<float>(spacing / std::sqrt((i + 1.0) * (i + 2.0)));
  }
}

// Fully unrolled for each dimension and free of data-dependent branches: the rank comparisons
// are coin flips, and mispredicted branches used to dominate the lattice construction.
template <int D>
inline void Embed(const float* scaled, Embedding<D>* e) {
  constexpr int kD1 = D + 1;
  constexpr float kInvD1 = 1.0f / kD1;
  // Elevate onto the hyperplane: column i has 1 in rows 0..i and -(i + 1) in row i + 1.
  float sum = 0.0f;
  for (int i = D; i > 0; --i) {
    const float cf = scaled[i - 1];
    e->elevated[i] = sum - static_cast<float>(i) * cf;
    sum += cf;
  }
  e->elevated[0] = sum;
  // Nearest point whose coordinates are multiples of d + 1 (rounding through 1.5 * 2^23, exact
  // for the coordinate range Build allows) ...
  constexpr float kRound = 12582912.0f;
  int coordinate_sum = 0;
  float delta[kD1];
  for (int i = 0; i < kD1; ++i) {
    const float r = (e->elevated[i] * kInvD1 + kRound) - kRound;
    const int q = static_cast<int>(r);
    coordinate_sum += q;
    e->rem0[i] = q * kD1;
    delta[i] = e->elevated[i] - static_cast<float>(e->rem0[i]);
    e->rank[i] = 0;
  }
  // ... ranked by elevated - rem0, largest first (ties: lower index first) ...
  for (int i = 0; i < kD1; ++i) {
    for (int j = i + 1; j < kD1; ++j) {
      const int smaller = delta[i] < delta[j] ? 1 : 0;
      e->rank[i] += smaller;
      e->rank[j] += 1 - smaller;
    }
  }
  // ... and moved back onto the hyperplane: when its coordinates sum to s (d + 1)-steps, the s
  // with the smallest differences step down (s > 0), or the -s with the largest step up (s < 0).
  // |s| <= (d + 1) / 2, so one wrap of the rotated ranks suffices.
  for (int i = 0; i < kD1; ++i) {
    const int r = e->rank[i] + coordinate_sum;
    const int down = r >= kD1 ? 1 : 0;
    const int up = r < 0 ? 1 : 0;
    e->rank[i] = r + kD1 * (up - down);
    e->rem0[i] += kD1 * (up - down);
  }
  // Barycentric weights from the differences sorted by rank: vertex k (k >= 1) gets
  // sorted[d - k] - sorted[d - k + 1], vertex 0 gets 1 + sorted[d] - sorted[0] (all / (d + 1)).
  float sorted[kD1];
  for (int i = 0; i < kD1; ++i) {
    sorted[e->rank[i]] = (e->elevated[i] - static_cast<float>(e->rem0[i])) * kInvD1;
  }
  e->barycentric[0] = 1.0f + sorted[D] - sorted[0];
  for (int k = 1; k < kD1; ++k) e->barycentric[k] = sorted[D - k] - sorted[D - k + 1];
  e->barycentric[D + 1] = 0.0f;
}

// Coordinate i of simplex vertex k: rem0 plus k, wrapped by d + 1 for the highest-ranked ones.
template <int D>
inline int VertexCoordinate(const Embedding<D>& e, int k, int i) {
  return e.rem0[i] + (e.rank[i] <= D - k ? k : k - (D + 1));
}

// The value that adds `delta` to field i of a packed key (fields never under- or overflow:
// Build bounds the coordinates).
inline uint64_t FieldDelta(int64_t delta, int i) {
  return static_cast<uint64_t>(delta) << (kFieldBits * (i % 3));
}

template <int D>
PermutohedralLattice::Simplex EmbedForTestImpl(const float* feature) {
  float scale[D];
  FeatureScales(D, scale);
  float scaled[D];
  for (int i = 0; i < D; ++i) scaled[i] = feature[i] * scale[i];
  Embedding<D> e;
  Embed<D>(scaled, &e);
  PermutohedralLattice::Simplex simplex;
  simplex.elevated.assign(e.elevated, e.elevated + D + 1);
  for (int k = 0; k <= D; ++k) {
    std::vector<int> vertex(D + 1);
    for (int i = 0; i <= D; ++i) vertex[i] = VertexCoordinate<D>(e, k, i);
    simplex.vertices.push_back(vertex);
    simplex.weights.push_back(e.barycentric[k]);
  }
  return simplex;
}

// Calls f(std::integral_constant<int, D>) for D = dim.
template <typename F>
auto DispatchDim(int dim, F&& f) {
  switch (dim) {
    case 1:
      return f(std::integral_constant<int, 1>());
    case 2:
      return f(std::integral_constant<int, 2>());
    case 3:
      return f(std::integral_constant<int, 3>());
    case 4:
      return f(std::integral_constant<int, 4>());
    case 5:
      return f(std::integral_constant<int, 5>());
    case 6:
      return f(std::integral_constant<int, 6>());
    default:
      MOSLAM_CHECK(false) << "unsupported lattice dimension " << dim;
  }
  return f(std::integral_constant<int, 1>());
}

}  // namespace

// Open addressing with linear probing. A slot holds its key next to the vertex index, so that a
// probe is one cache access; vertex numbers follow insertion order (deterministic).
class PermutohedralLattice::HashTable {
 public:
  // Empties *keys and the table, keeping their memory.
  void Reset(std::vector<Key>* keys, size_t expected) {
    keys_ = keys;
    keys_->clear();
    size_t capacity = 1024;
    while (capacity < 2 * expected) capacity *= 2;
    Resize(capacity);
  }

  uint32_t FindOrInsert(const Key& key) {
    size_t h = Hash(key) & mask_;
    while (true) {
      const int32_t index = slot_index_[h];
      if (index < 0) break;
      if (slot_keys_[h] == key) return static_cast<uint32_t>(index);
      h = (h + 1) & mask_;
    }
    const auto index = static_cast<int32_t>(keys_->size());
    keys_->push_back(key);
    slot_keys_[h] = key;
    slot_index_[h] = index;
    if (2 * keys_->size() > slot_index_.size()) Grow();
    return static_cast<uint32_t>(index);
  }

  // The vertex with `key`, or -1.
  int32_t Find(const Key& key) const {
    size_t h = Hash(key) & mask_;
    while (true) {
      const int32_t index = slot_index_[h];
      if (index < 0 || slot_keys_[h] == key) return index;
      h = (h + 1) & mask_;
    }
  }

 private:
  static size_t Hash(const Key& key) {
    const uint64_t h = (key.lo ^ (key.hi * 0xC2B2AE3D27D4EB4Full)) * 0x9E3779B97F4A7C15ull;
    return static_cast<size_t>(h ^ (h >> 32));
  }

  void Resize(size_t capacity) {
    slot_keys_.assign(capacity, Key{});
    slot_index_.assign(capacity, -1);
    mask_ = capacity - 1;
  }

  void Grow() {
    Resize(slot_index_.size() * 2);
    for (size_t i = 0; i < keys_->size(); ++i) {
      size_t h = Hash((*keys_)[i]) & mask_;
      while (slot_index_[h] >= 0) h = (h + 1) & mask_;
      slot_keys_[h] = (*keys_)[i];
      slot_index_[h] = static_cast<int32_t>(i);
    }
  }

  std::vector<Key>* keys_ = nullptr;
  std::vector<Key> slot_keys_;
  std::vector<int32_t> slot_index_;
  size_t mask_ = 0;
};

PermutohedralLattice::PermutohedralLattice()
    : table_(std::make_unique<HashTable>()),
      chunk_tables_(std::make_unique<HashTable[]>(kSplatChunks)) {}
PermutohedralLattice::~PermutohedralLattice() = default;
PermutohedralLattice::PermutohedralLattice(PermutohedralLattice&&) noexcept = default;
PermutohedralLattice& PermutohedralLattice::operator=(PermutohedralLattice&&) noexcept = default;

int PermutohedralLattice::PaddedStride(int channels) {
  MOSLAM_CHECK(channels >= 1 && channels <= kMaxStride) << "channels " << channels;
  if (channels <= 2) return channels;
  return (channels + 3) / 4 * 4;
}

PermutohedralLattice::Simplex PermutohedralLattice::EmbedForTest(const float* feature, int dim) {
  return DispatchDim(dim, [&](auto d) { return EmbedForTestImpl<decltype(d)::value>(feature); });
}

void PermutohedralLattice::Build(const float* features, int num_points, int dim,
                                 const uint8_t* active, ThreadPool* pool) {
  MOSLAM_CHECK(dim >= 1 && dim <= kMaxDim) << "dim " << dim;
  MOSLAM_CHECK_GE(num_points, 0);
  dim_ = dim;
  num_points_ = num_points;
  const int d1 = dim + 1;
  const size_t n = static_cast<size_t>(num_points);
  point_vertex_.resize(n * d1);
  point_weight_.resize(n * d1);
  splat_scale_.assign(n, 1.0f);
  slice_scale_.assign(n, 1.0f);
  const auto run = [pool](int64_t count, const auto& fn) {
    if (pool != nullptr) {
      pool->ParallelFor(count, fn);
    } else {
      fn(int64_t{0}, count);
    }
  };

  // 1. Each chunk of points embeds its points and numbers their vertices in a table of its own.
  std::vector<Key>* chunk_keys = chunk_keys_;
  run(kSplatChunks, [&](int64_t begin, int64_t end) {
    for (int64_t c = begin; c < end; ++c) {
      DispatchDim(dim, [&](auto d) {
        EmbedChunk<decltype(d)::value>(features, active, ChunkBegin(c), ChunkBegin(c + 1),
                                       &chunk_tables_[c], &chunk_keys[c]);
        return 0;
      });
    }
  });
  // 2. One table for all: chunk by chunk, in order, so the numbering is the same whatever the
  // threads (the filter's sums do not depend on the numbering anyway).
  HashTable& table = *table_;
  table.Reset(&keys_, chunk_keys[0].size() * 2);
  std::vector<uint32_t> to_global[kSplatChunks];
  std::vector<uint8_t> chunk_masks;
  for (int c = 0; c < kSplatChunks; ++c) {
    to_global[c].resize(chunk_keys[c].size() + 1);
    for (size_t local = 0; local < chunk_keys[c].size(); ++local) {
      const uint32_t v = table.FindOrInsert(chunk_keys[c][local]);
      to_global[c][local] = v;
      if (chunk_masks.size() <= v) chunk_masks.resize(2 * (v + 1), 0);
      chunk_masks[v] |= static_cast<uint8_t>(1u << c);
    }
  }
  num_vertices_ = static_cast<int>(keys_.size());
  chunk_masks.resize(keys_.size());
  // 3. Local numbers to global ones; inactive points (local number "one past the end") point at
  // the zero vertex M.
  run(kSplatChunks, [&](int64_t begin, int64_t end) {
    for (int64_t c = begin; c < end; ++c) {
      std::vector<uint32_t>& map = to_global[c];
      map.back() = static_cast<uint32_t>(num_vertices_);
      const size_t past_end = map.size() - 1;
      for (size_t s = ChunkBegin(c) * d1; s < ChunkBegin(c + 1) * d1; ++s) {
        point_vertex_[s] = map[std::min<size_t>(point_vertex_[s], past_end)];
      }
    }
  });
  BuildNeighbours(table, pool);
  BuildSplatRows(chunk_masks);
}

template <int D>
void PermutohedralLattice::EmbedChunk(const float* features, const uint8_t* active, size_t begin,
                                      size_t end, HashTable* chunk_table, std::vector<Key>* keys) {
  constexpr int kD1 = D + 1;
  float scale[D];
  FeatureScales(D, scale);
  HashTable& table = *chunk_table;
  table.Reset(keys, (end - begin) / 8 + 16);
  // Packed offsets: +1 on every stored coordinate, and d + 1 on one of them.
  Key ones;
  Key unit[D];
  for (int i = 0; i < D; ++i) {
    (i < 3 ? ones.lo : ones.hi) += FieldDelta(1, i);
    unit[i] = Key{};
    (i < 3 ? unit[i].lo : unit[i].hi) = FieldDelta(kD1, i);
  }
  // Neighbouring pixels often fall in the same simplex: reuse the previous point's vertices when
  // its rem0 and ranks agree.
  Key previous_key;
  uint32_t previous_ranks = ~0u;
  const uint32_t* previous_vertices = nullptr;
  bool all_finite = true;
  Embedding<D> e;
  for (size_t p = begin; p < end; ++p) {
    uint32_t* vertices = &point_vertex_[p * kD1];
    float* weights = &point_weight_[p * kD1];
    if (active != nullptr && active[p] == 0) {
      std::fill_n(weights, kD1, 0.0f);
      std::fill_n(vertices, kD1, ~0u);  // becomes M
      continue;
    }
    const float* f = features + p * D;
    float scaled[D];
    float magnitude = 0.0f;
    for (int i = 0; i < D; ++i) {
      all_finite &= (f[i] - f[i] == 0.0f);
      scaled[i] = f[i] * scale[i];
      magnitude += std::fabs(scaled[i]) * static_cast<float>(i + 1);
    }
    // |elevated_i| <= sum_j (j + 1) |scaled_j|; NaN fails the comparison too.
    if (!(magnitude < kMaxCoordinate)) {
      if (!all_finite) ThrowInput("lattice: a feature of point {} is not finite", p);
      ThrowInput(
          "lattice: features of point {} are too large ({}) for the lattice coordinates; use "
          "larger standard deviations",
          p, magnitude);
    }
    Embed<D>(scaled, &e);
    std::copy(e.barycentric, e.barycentric + kD1, weights);
    Key key;
    uint32_t ranks = 0;
    int index_of_rank[kD1];
    for (int i = 0; i < kD1; ++i) {
      ranks |= static_cast<uint32_t>(e.rank[i]) << (3 * i);
      index_of_rank[e.rank[i]] = i;
    }
    for (int i = 0; i < D; ++i) {
      (i < 3 ? key.lo : key.hi) |= FieldDelta(e.rem0[i] + kBias, i);
    }
    if (previous_vertices != nullptr && key == previous_key && ranks == previous_ranks) {
      std::copy(previous_vertices, previous_vertices + kD1, vertices);
      continue;
    }
    previous_key = key;
    previous_ranks = ranks;
    previous_vertices = vertices;
    // Vertex k = vertex k - 1 + 1 everywhere, minus d + 1 on the coordinate ranked d - k + 1.
    vertices[0] = table.FindOrInsert(key);
    for (int k = 1; k < kD1; ++k) {
      key.lo += ones.lo;
      key.hi += ones.hi;
      const int i = index_of_rank[D - k + 1];
      if (i < D) {
        key.lo -= unit[i].lo;
        key.hi -= unit[i].hi;
      }
      vertices[k] = table.FindOrInsert(key);
    }
  }
  if (!all_finite) ThrowInput("lattice: a feature is not finite");
}

void PermutohedralLattice::BuildNeighbours(const HashTable& table, ThreadPool* pool) {
  const int d1 = dim_ + 1;
  const int64_t m = num_vertices_;
  neighbours_.resize(static_cast<size_t>(d1) * m * 2);
  // Along direction j, the neighbour "down" is the vertex minus 1 in every coordinate except j,
  // which gains d (and "up" the opposite).
  std::vector<Key> down_offset(d1);
  for (int j = 0; j < d1; ++j) {
    for (int i = 0; i < dim_; ++i) {
      (i < 3 ? down_offset[j].lo : down_offset[j].hi) += FieldDelta(i == j ? dim_ : -1, i);
    }
  }
  const auto body = [&](int64_t begin, int64_t end) {
    for (int j = 0; j < d1; ++j) {
      const Key& o = down_offset[j];
      uint32_t* out = &neighbours_[static_cast<size_t>(j) * m * 2];
      for (int64_t v = begin; v < end; ++v) {
        const Key& key = keys_[v];
        const int32_t a = table.Find(Key{key.lo + o.lo, key.hi + o.hi});
        const int32_t b = table.Find(Key{key.lo - o.lo, key.hi - o.hi});
        out[2 * v] = a < 0 ? static_cast<uint32_t>(m) : static_cast<uint32_t>(a);
        out[2 * v + 1] = b < 0 ? static_cast<uint32_t>(m) : static_cast<uint32_t>(b);
      }
    }
  };
  if (pool != nullptr) {
    pool->ParallelFor(m, body);
  } else {
    body(0, m);
  }
}

void PermutohedralLattice::BuildSplatRows(const std::vector<uint8_t>& chunk_masks) {
  const size_t m = static_cast<size_t>(num_vertices_);
  splat_row_.resize(m);
  splat_step_.resize(m);
  shared_vertices_.clear();
  for (size_t v = 0; v < m; ++v) {
    const bool shared = std::bitset<8>(chunk_masks[v]).count() > 1;
    splat_step_[v] = shared ? 1 : 0;
    if (shared) {
      splat_row_[v] = static_cast<uint32_t>(m + 1 + shared_vertices_.size() * kSplatChunks);
      shared_vertices_.push_back(static_cast<uint32_t>(v));
    } else {
      splat_row_[v] = static_cast<uint32_t>(v);
    }
  }
}

void PermutohedralLattice::ScaleWeights(const float* splat_scale, const float* slice_scale) {
  for (int p = 0; p < num_points_; ++p) {
    if (splat_scale != nullptr) splat_scale_[p] *= splat_scale[p];
    if (slice_scale != nullptr) slice_scale_[p] *= slice_scale[p];
  }
}

simd::LatticeArrays PermutohedralLattice::Arrays() const {
  simd::LatticeArrays a;
  a.dim = dim_;
  a.num_vertices = static_cast<uint32_t>(num_vertices_);
  a.point_vertex = point_vertex_.data();
  a.point_weight = point_weight_.data();
  a.splat_scale = splat_scale_.data();
  a.slice_scale = slice_scale_.data();
  a.splat_row = splat_row_.data();
  a.splat_step = splat_step_.data();
  a.shared_vertices = shared_vertices_.data();
  a.splat_chunks = kSplatChunks;
  return a;
}

void PermutohedralLattice::Filter(const float* in, float* out, int stride, bool accumulate,
                                  ThreadPool* pool) {
  MOSLAM_CHECK_EQ(stride, PaddedStride(stride));
  const simd::Kernels& kernels = simd::Active();
  const simd::LatticeArrays a = Arrays();
  const int d1 = dim_ + 1;
  const int64_t m = num_vertices_;
  const size_t rows = static_cast<size_t>(m + 1) + shared_vertices_.size() * kSplatChunks;
  const auto run = [pool](int64_t count, const std::function<void(int64_t, int64_t)>& fn) {
    if (pool != nullptr) {
      pool->ParallelFor(count, fn);
    } else {
      fn(0, count);
    }
  };
  values_.resize(rows * stride);
  run(static_cast<int64_t>(rows), [&](int64_t begin, int64_t end) {
    std::fill(values_.begin() + begin * stride, values_.begin() + end * stride, 0.0f);
  });
  scratch_.resize(static_cast<size_t>(m + 1) * stride);
  std::fill_n(&scratch_[static_cast<size_t>(m) * stride], stride, 0.0f);
  // Splat: each chunk of points scatters, in point order, into its vertices' rows; vertices
  // touched by several chunks get the chunks' rows added in chunk order.
  float* values = values_.data();
  run(kSplatChunks, [&](int64_t begin, int64_t end) {
    for (int64_t c = begin; c < end; ++c) {
      kernels.splat(a, in, values, stride, c, ChunkBegin(c), ChunkBegin(c + 1));
    }
  });
  run(static_cast<int64_t>(shared_vertices_.size()),
      [&](int64_t begin, int64_t end) { kernels.merge(a, values, stride, begin, end); });
  // Blur along each lattice direction in turn.
  float* src = values_.data();
  float* dst = scratch_.data();
  for (int j = 0; j < d1; ++j) {
    const uint32_t* nb = &neighbours_[static_cast<size_t>(j) * m * 2];
    run(m, [&](int64_t begin, int64_t end) { kernels.blur(src, dst, nb, stride, begin, end); });
    std::swap(src, dst);
  }
  // Slice: every point reads its simplex's vertices.
  run(num_points_, [&](int64_t begin, int64_t end) {
    kernels.slice(a, src, out, stride, accumulate, begin, end);
  });
}

}  // namespace moslam::semantic
