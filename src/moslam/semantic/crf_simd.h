// The CRF's inner loops (lattice splat/blur/slice, unary energies, mean-field update), compiled
// once per instruction set from crf_simd_impl.inc: 4-float vectors for any CPU (SSE2 on x86-64),
// and 8-float vectors with FMA for CPUs with AVX2, chosen at run time. The sets differ in the
// last bits (FMA rounds once); within one process every call uses the same set, so results do
// not depend on the number of threads.
#pragma once

#include <cstddef>
#include <cstdint>

namespace moslam::semantic::simd {

// The lattice arrays the filter loops read (see PermutohedralLattice).
struct LatticeArrays {
  int dim = 0;
  uint32_t num_vertices = 0;
  const uint32_t* point_vertex = nullptr;  // per point, d + 1 vertices (M: inactive)
  const float* point_weight = nullptr;     // per point, d + 1 barycentric weights
  const float* splat_scale = nullptr;      // per point
  const float* slice_scale = nullptr;      // per point
  const uint32_t* splat_row = nullptr;     // per vertex
  const uint8_t* splat_step = nullptr;     // per vertex
  const uint32_t* shared_vertices = nullptr;
  int splat_chunks = 1;
};

// Inputs of the unary-energy pass: unaries as planar {L, H, W} or interleaved H x W x L.
struct EnergyArgs {
  int labels = 0;
  int64_t num_pixels = 0;
  const float* values = nullptr;
  bool planar = true;
  bool probabilities = true;
  float min_probability = 0.0f;
  float* energies = nullptr;  // tiles of `tile` pixels x L labels, label-major in a tile
  float* q = nullptr;         // N x stride: the first Q (labels 0 .. L - 2)
};

// Inputs of one mean-field update (see UpdateTiles in crf_simd_impl.inc).
struct UpdateArgs {
  int labels = 0;
  int64_t num_pixels = 0;
  const float* energies = nullptr;
  const float* message = nullptr;        // N x stride, or null: the unary-only step
  const float* ones_message = nullptr;   // N
  const float* compatibility = nullptr;  // L x L, or null: Potts
  float* q = nullptr;                    // N x stride
  float* marginals = nullptr;            // planar {L, N}, or null
  uint8_t* labels_out = nullptr;         // N, with marginals
};

struct Kernels {
  const char* name;
  int tile;  // pixels per energy/update tile
  // values (vertex rows) += splat of points [begin, end) of splat chunk `chunk`.
  void (*splat)(const LatticeArrays& a, const float* in, float* values, int stride, int64_t chunk,
                int64_t begin, int64_t end);
  // Rows of the shared vertices [begin, end) = sum of their per-chunk rows.
  void (*merge)(const LatticeArrays& a, float* values, int stride, int64_t begin, int64_t end);
  // dst[v] = src[v] + (src[n1] + src[n2]) / 2 for vertices [begin, end).
  void (*blur)(const float* src, float* dst, const uint32_t* neighbours, int stride, int64_t begin,
               int64_t end);
  // out (+)= slice of points [begin, end).
  void (*slice)(const LatticeArrays& a, const float* values, float* out, int stride,
                bool accumulate, int64_t begin, int64_t end);
  // Tiles [begin, end); returns false when a value is NaN or infinite.
  bool (*energies)(const EnergyArgs& e, int stride, int64_t begin, int64_t end);
  // Tiles [begin, end).
  void (*update)(const UpdateArgs& u, int stride, int64_t begin, int64_t end);
  // For tests: out[i] = exp(in[i]) and log(in[i]) with this set's approximations.
  void (*exp)(const float* in, float* out, int64_t n);
  void (*log)(const float* in, float* out, int64_t n);
};

const Kernels& Portable();
// The AVX2 + FMA set, or null when not built or when the CPU lacks it.
const Kernels* Avx2();
// The set in use: Avx2() when available unless the environment variable MOSLAM_SIMD is
// "portable", else Portable().
const Kernels& Active();

}  // namespace moslam::semantic::simd
