// Gaussian filtering in a d-dimensional feature space with the permutohedral lattice (A. Adams,
// J. Baek, M. A. Davis, "Fast high-dimensional filtering using the permutohedral lattice",
// Eurographics 2010), the filter behind the fully connected CRF of Krähenbühl and Koltun.
//
// Each point (a pixel) is embedded in the lattice, where it lies in one simplex of d + 1 vertices
// with barycentric weights. Filtering splats point values onto those vertices, blurs the vertex
// values with [1/2 1 1/2] along each of the d + 1 lattice directions, and slices them back. Up to
// a constant factor this approximates
//
//   out_i = sum_j exp(-|f_i - f_j|^2 / 2) in_j        (the j = i term included)
//
// for features f already divided by their standard deviations. Normalized uses (the CRF) do not
// depend on the constant factor.
//
// The lattice is built once per image (Build) and then filters any number of value vectors
// (Filter): all channels of a point travel together as one contiguous row. Splatting scatters
// points in order into the vertex rows; to keep sums in a fixed order whatever the number of
// threads, the points are cut into kSplatChunks fixed ranges, and a vertex touched by several
// ranges gets one row per range, added up in range order afterwards.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace moslam::semantic {

class ThreadPool;
namespace simd {
struct LatticeArrays;
}

class PermutohedralLattice {
 public:
  // Largest feature dimension (position + colour is 5, position + depth 3).
  static constexpr int kMaxDim = 6;
  // Largest row stride Filter accepts; rows are padded to kStrides (see PaddedStride).
  static constexpr int kMaxStride = 32;

  PermutohedralLattice();
  ~PermutohedralLattice();
  PermutohedralLattice(PermutohedralLattice&&) noexcept;
  PermutohedralLattice& operator=(PermutohedralLattice&&) noexcept;

  // The smallest supported row stride >= channels: 1, 2, 4, then multiples of 4 up to 32.
  static int PaddedStride(int channels);

  // Embeds `num_points` feature rows of `dim` floats (row-major). Points with active[i] == 0
  // (active may be null: all active) are left out: they give nothing and receive nothing. Throws
  // InputError when an active point's features are not finite or so large (relative to 1, the
  // standard deviation) that the lattice coordinates would overflow. `pool` may be null.
  void Build(const float* features, int num_points, int dim, const uint8_t* active,
             ThreadPool* pool = nullptr);

  int dim() const { return dim_; }
  int num_points() const { return num_points_; }
  int num_vertices() const { return num_vertices_; }

  // Multiplies the splat weight of point i by splat_scale[i] and its slice weight by
  // slice_scale[i] (either may be null), e.g. a normalization and a kernel weight.
  void ScaleWeights(const float* splat_scale, const float* slice_scale);

  // Filters rows of `stride` floats (stride == PaddedStride(stride)): out_i = sum over the simplex
  // vertices v of point i of w_iv * blurred(v), where blurred = blur(sum over points j of w_jv
  // in_j). With accumulate, adds to out instead of overwriting; inactive points' rows are left
  // unchanged (accumulate) or set to zero. `pool` may be null (one thread).
  void Filter(const float* in, float* out, int stride, bool accumulate, ThreadPool* pool);

  // For tests: the simplex of point i, as vertex lattice coordinates (d + 1 integers each, in
  // the scaled hyperplane coordinates) and barycentric weights; the elevated position is their
  // weighted sum.
  struct Simplex {
    std::vector<std::vector<int>> vertices;
    std::vector<float> weights;
    std::vector<float> elevated;
  };
  static Simplex EmbedForTest(const float* feature, int dim);

 private:
  struct Key {
    uint64_t lo = 0;
    uint64_t hi = 0;
    bool operator==(const Key& other) const { return lo == other.lo && hi == other.hi; }
  };
  class HashTable;

  // Points [begin, end): barycentric weights, and vertex numbers in a table of their own whose
  // keys end up in *keys (inactive points get ~0).
  template <int D>
  void EmbedChunk(const float* features, const uint8_t* active, size_t begin, size_t end,
                  HashTable* chunk_table, std::vector<Key>* keys);
  void BuildNeighbours(const HashTable& table, ThreadPool* pool);
  // First point of splat chunk c (c = kSplatChunks: num_points).
  size_t ChunkBegin(int64_t c) const {
    return static_cast<size_t>(static_cast<int64_t>(num_points_) * c / kSplatChunks);
  }
  void BuildSplatRows(const std::vector<uint8_t>& chunk_masks);
  // The arrays the filter loops (crf_simd.h) read.
  simd::LatticeArrays Arrays() const;

  static constexpr int kSplatChunks = 4;

  int dim_ = 0;
  int num_points_ = 0;
  int num_vertices_ = 0;
  std::vector<Key> keys_;  // Per vertex, its packed lattice coordinates.
  // Hash tables and vertex keys of the build, kept to reuse their memory.
  std::unique_ptr<HashTable> table_;
  std::unique_ptr<HashTable[]> chunk_tables_;
  std::vector<Key> chunk_keys_[kSplatChunks];
  // Per point, d + 1 vertices and barycentric weights (inactive points: vertex M, weight 0).
  std::vector<uint32_t> point_vertex_;
  std::vector<float> point_weight_;
  std::vector<float> splat_scale_;  // per point
  std::vector<float> slice_scale_;  // per point
  // Splat destination of vertex v for chunk c: row splat_row_[v] + c * splat_step_[v] (step 0:
  // only one chunk touches v, its row is v; step 1: one row per chunk after the M + 1 rows).
  std::vector<uint32_t> splat_row_;
  std::vector<uint8_t> splat_step_;
  std::vector<uint32_t> shared_vertices_;  // the vertices with step 1, in order
  // Per lattice direction j and vertex v: the two neighbours along j at
  // neighbours_[(j * M + v) * 2 + {0, 1}] (M, the zero vertex, when absent).
  std::vector<uint32_t> neighbours_;
  // Vertex values: M rows, the zero row M, then the per-chunk rows of shared vertices.
  std::vector<float> values_;
  std::vector<float> scratch_;
};

}  // namespace moslam::semantic
