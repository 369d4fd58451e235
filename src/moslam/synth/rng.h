// A small seeded random generator whose output is the same on every platform and standard library,
// so that a preset and seed give byte-identical sequences (std::normal_distribution and the other
// <random> distributions are implementation-defined; only the engines are specified).
#pragma once

#include <cmath>
#include <cstdint>

namespace moslam::synth {

// SplitMix64 (Steele, Lea & Flood, OOPSLA 2014): one 64-bit state, good enough statistics for
// textures and sensor noise, and trivially seedable from (seed, stream) pairs.
class Rng {
 public:
  explicit Rng(uint64_t seed, uint64_t stream = 0)
      : state_(seed * 0x9E3779B97F4A7C15ULL + Mix(stream + 0x632BE59BD9B4E019ULL)) {}

  uint64_t Next() {
    state_ += 0x9E3779B97F4A7C15ULL;
    return Mix(state_);
  }
  // Uniform in [0, 1) with 53 random bits.
  double Uniform() { return static_cast<double>(Next() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Uniform integer in [0, n); n > 0.
  int Index(int n) { return static_cast<int>(Uniform() * n); }
  // Standard normal by the Box-Muller transform; the second value of each pair is kept.
  double Normal() {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    double u1 = Uniform();
    while (u1 <= 0.0) u1 = Uniform();
    const double u2 = Uniform();
    const double r = std::sqrt(-2.0 * std::log(u1));
    spare_ = r * std::sin(2.0 * M_PI * u2);
    has_spare_ = true;
    return r * std::cos(2.0 * M_PI * u2);
  }
  double Normal(double mean, double sigma) { return mean + sigma * Normal(); }

  static uint64_t Mix(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }

 private:
  uint64_t state_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

}  // namespace moslam::synth
