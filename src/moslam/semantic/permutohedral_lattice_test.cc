#include "moslam/semantic/permutohedral_lattice.h"

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "moslam/semantic/thread_pool.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

std::vector<float> RandomFeatures(int n, int dim, float range, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> uniform(0.0f, range);
  std::vector<float> f(static_cast<size_t>(n) * dim);
  for (float& v : f) v = uniform(rng);
  return f;
}

// Exact normalized Gaussian filter: sum_j k_ij v_j / sum_j k_ij, k = exp(-|f_i - f_j|^2 / 2 s^2).
std::vector<double> ExactNormalized(const std::vector<float>& f, int dim,
                                    const std::vector<float>& v, double sigma) {
  const size_t n = v.size();
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) {
    double num = 0.0;
    double den = 0.0;
    for (size_t j = 0; j < n; ++j) {
      double d2 = 0.0;
      for (int c = 0; c < dim; ++c) {
        const double d = f[i * dim + c] - f[j * dim + c];
        d2 += d * d;
      }
      const double k = std::exp(-0.5 * d2 / (sigma * sigma));
      num += k * v[j];
      den += k;
    }
    out[i] = num / den;
  }
  return out;
}

TEST(PermutohedralLattice, SimplexContainsThePointWithBarycentricWeights) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> uniform(-50.0f, 50.0f);
  for (int dim = 1; dim <= PermutohedralLattice::kMaxDim; ++dim) {
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<float> f(dim);
      for (float& v : f) v = uniform(rng);
      const auto s = PermutohedralLattice::EmbedForTest(f.data(), dim);
      ASSERT_EQ(s.vertices.size(), static_cast<size_t>(dim + 1));
      double weight_sum = 0.0;
      std::vector<double> position(dim + 1, 0.0);
      for (int k = 0; k <= dim; ++k) {
        EXPECT_GE(s.weights[k], -1e-4f) << "dim " << dim;
        weight_sum += s.weights[k];
        int coordinate_sum = 0;
        for (int i = 0; i <= dim; ++i) {
          // Vertex k is a remainder-k point: every coordinate is k modulo d + 1.
          EXPECT_EQ(((s.vertices[k][i] % (dim + 1)) + dim + 1) % (dim + 1), k);
          coordinate_sum += s.vertices[k][i];
          position[i] += s.weights[k] * s.vertices[k][i];
        }
        EXPECT_EQ(coordinate_sum, 0);
      }
      EXPECT_NEAR(weight_sum, 1.0, 1e-5);
      for (int i = 0; i <= dim; ++i) EXPECT_NEAR(position[i], s.elevated[i], 1e-3);
    }
  }
}

struct Accuracy {
  double max_error = 0.0;
  double mean_error = 0.0;
};

// Compares the lattice's normalized filter of random values at random points with the exact
// filter of standard deviation `sigma`.
Accuracy FilterAccuracy(int n, int dim, float range, uint32_t seed, double sigma) {
  const std::vector<float> f = RandomFeatures(n, dim, range, seed);
  std::mt19937 rng(seed + 1);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  std::vector<float> v(n);
  for (float& x : v) x = uniform(rng);
  PermutohedralLattice lattice;
  lattice.Build(f.data(), n, dim, nullptr);
  std::vector<float> ones(n, 1.0f), num(n), den(n);
  lattice.Filter(v.data(), num.data(), 1, false, nullptr);
  lattice.Filter(ones.data(), den.data(), 1, false, nullptr);
  const std::vector<double> exact = ExactNormalized(f, dim, v, sigma);
  Accuracy a;
  for (int i = 0; i < n; ++i) {
    const double e = std::fabs(num[i] / den[i] - exact[i]);
    a.max_error = std::max(a.max_error, e);
    a.mean_error += e / n;
  }
  return a;
}

TEST(PermutohedralLattice, ApproximatesANormalizedGaussianOfUnitStandardDeviation) {
  for (int dim : {2, 3, 5}) {
    // Points dense enough that every one has neighbours within a standard deviation.
    const float range = dim == 5 ? 4.0f : 8.0f;
    const Accuracy a = FilterAccuracy(1500, dim, range, 11 + dim, 1.0);
    // Values are uniform in [0, 1] (spread 0.29); a broken splat/slice gives errors of that order.
    EXPECT_LT(a.mean_error, 0.01) << "dim " << dim;
    EXPECT_LT(a.max_error, 0.06) << "dim " << dim;
    // The blur has the right width: the exact filter with sigma 1 matches much better than with
    // 0.7 or 1.4.
    const Accuracy narrow = FilterAccuracy(1500, dim, range, 11 + dim, 0.7);
    const Accuracy wide = FilterAccuracy(1500, dim, range, 11 + dim, 1.4);
    EXPECT_LT(a.mean_error, 0.7 * std::min(narrow.mean_error, wide.mean_error)) << "dim " << dim;
  }
}

// A lattice over random 3-D points, half of them inactive, and a random 4-channel signal.
struct Scene {
  int n = 800;
  int dim = 3;
  std::vector<float> features;
  std::vector<uint8_t> active;
  std::vector<float> values;
};

Scene MakeScene() {
  Scene s;
  s.features = RandomFeatures(s.n, s.dim, 5.0f, 3);
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  s.active.resize(s.n);
  for (int i = 0; i < s.n; ++i) s.active[i] = (i % 3 != 0) ? 1 : 0;
  s.values.resize(static_cast<size_t>(s.n) * 4);
  for (float& v : s.values) v = uniform(rng);
  return s;
}

TEST(PermutohedralLattice, InactivePointsNeitherGiveNorReceive) {
  Scene s = MakeScene();
  PermutohedralLattice lattice;
  lattice.Build(s.features.data(), s.n, s.dim, s.active.data());
  std::vector<float> before(s.values.size()), after(s.values.size());
  lattice.Filter(s.values.data(), before.data(), 4, false, nullptr);
  // Changing the values (and the features) of inactive points changes nothing.
  for (int i = 0; i < s.n; ++i) {
    if (s.active[i] != 0) continue;
    for (int c = 0; c < 4; ++c) s.values[i * 4 + c] = 1000.0f;
    s.features[i * s.dim] = std::numeric_limits<float>::quiet_NaN();
  }
  PermutohedralLattice rebuilt;
  rebuilt.Build(s.features.data(), s.n, s.dim, s.active.data());
  rebuilt.Filter(s.values.data(), after.data(), 4, false, nullptr);
  int active_nonzero = 0;
  for (int i = 0; i < s.n; ++i) {
    for (int c = 0; c < 4; ++c) {
      EXPECT_EQ(before[i * 4 + c], after[i * 4 + c]) << "point " << i;
      if (s.active[i] == 0) {
        EXPECT_EQ(after[i * 4 + c], 0.0f) << "point " << i;
      }
      if (s.active[i] != 0 && after[i * 4 + c] != 0.0f) ++active_nonzero;
    }
  }
  EXPECT_GT(active_nonzero, s.n);
}

TEST(PermutohedralLattice, ResultDoesNotDependOnThreadsOrStride) {
  const Scene s = MakeScene();
  PermutohedralLattice lattice;
  lattice.Build(s.features.data(), s.n, s.dim, s.active.data());
  std::vector<float> one_thread(s.values.size()), two_threads(s.values.size());
  lattice.Filter(s.values.data(), one_thread.data(), 4, false, nullptr);
  ThreadPool pool(2);
  lattice.Filter(s.values.data(), two_threads.data(), 4, false, &pool);
  EXPECT_EQ(one_thread, two_threads);
  // Channel 2 filtered alone (stride 1) equals channel 2 of the 4-channel filter.
  std::vector<float> channel(s.n), filtered(s.n);
  for (int i = 0; i < s.n; ++i) channel[i] = s.values[i * 4 + 2];
  lattice.Filter(channel.data(), filtered.data(), 1, false, &pool);
  for (int i = 0; i < s.n; ++i) EXPECT_FLOAT_EQ(filtered[i], one_thread[i * 4 + 2]);
}

TEST(PermutohedralLattice, AccumulateAddsToTheOutput) {
  const Scene s = MakeScene();
  PermutohedralLattice lattice;
  lattice.Build(s.features.data(), s.n, s.dim, nullptr);
  std::vector<float> once(s.values.size()), twice(s.values.size());
  lattice.Filter(s.values.data(), once.data(), 4, false, nullptr);
  lattice.Filter(s.values.data(), twice.data(), 4, false, nullptr);
  lattice.Filter(s.values.data(), twice.data(), 4, true, nullptr);
  for (size_t i = 0; i < once.size(); ++i) EXPECT_FLOAT_EQ(twice[i], 2.0f * once[i]);
}

TEST(PermutohedralLattice, ScaleWeightsScalesSplatAndSlice) {
  const Scene s = MakeScene();
  PermutohedralLattice plain, scaled;
  plain.Build(s.features.data(), s.n, s.dim, nullptr);
  scaled.Build(s.features.data(), s.n, s.dim, nullptr);
  std::vector<float> a(s.n), b(s.n);
  for (int i = 0; i < s.n; ++i) {
    a[i] = 0.5f + 0.001f * i;
    b[i] = 2.0f - 0.001f * i;
  }
  scaled.ScaleWeights(a.data(), b.data());
  // scaled(v) = b * plain(a * v)
  std::vector<float> v(s.n), av(s.n), expected(s.n), got(s.n);
  for (int i = 0; i < s.n; ++i) {
    v[i] = s.values[i * 4];
    av[i] = a[i] * v[i];
  }
  plain.Filter(av.data(), expected.data(), 1, false, nullptr);
  scaled.Filter(v.data(), got.data(), 1, false, nullptr);
  for (int i = 0; i < s.n; ++i)
    EXPECT_NEAR(got[i], b[i] * expected[i], 1e-4f * std::fabs(expected[i]) + 1e-5f);
}

TEST(PermutohedralLattice, RejectsNonFiniteAndHugeFeatures) {
  std::vector<float> f = {0.0f, 0.0f, 1.0f, std::numeric_limits<float>::infinity()};
  PermutohedralLattice lattice;
  EXPECT_THROW(lattice.Build(f.data(), 2, 2, nullptr), InputError);
  f[3] = 1e7f;
  EXPECT_THROW(lattice.Build(f.data(), 2, 2, nullptr), InputError);
  f[3] = 1e4f;
  EXPECT_NO_THROW(lattice.Build(f.data(), 2, 2, nullptr));
  EXPECT_EQ(lattice.num_vertices(), 6);  // two far-apart points, three vertices each
}

}  // namespace
}  // namespace moslam::semantic
