// The CRF's pairwise kernels, internal to dense_crf.cc: each one, prepared for an image, applies
// w D^-1/2 K D^-1/2 to rows of label values (Krähenbühl's symmetric normalization, D = diag(K 1)).
//
// Two filters implement K: the permutohedral lattice (any features), and for the smoothness
// kernel with few channels an exact separable Gaussian blur, which is cheaper than building a
// lattice when there is little to filter.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/semantic/permutohedral_lattice.h"

namespace moslam::semantic {

class ThreadPool;

class PairwiseKernel {
 public:
  virtual ~PairwiseKernel() = default;
  // out (+)= w D^-1/2 K D^-1/2 in, rows of `stride` floats, one per pixel.
  virtual void Apply(const float* in, float* out, int stride, bool accumulate,
                     ThreadPool* pool) = 0;
  // w D^-1/2 K D^-1/2 1, per pixel.
  const std::vector<float>& filtered_ones() const { return filtered_ones_; }

 protected:
  std::vector<float> filtered_ones_;
};

// Features are rows of `dim` floats divided by their standard deviations; active may be null.
class LatticeKernel : public PairwiseKernel {
 public:
  void Prepare(const float* features, int num_pixels, int dim, const uint8_t* active, float weight,
               ThreadPool* pool);
  void Apply(const float* in, float* out, int stride, bool accumulate, ThreadPool* pool) override;

 private:
  PermutohedralLattice lattice_;
  std::vector<float> ones_;
  std::vector<float> norm_;
  std::vector<float> slice_scale_;
};

// exp(-|p_i - p_j|^2 / 2 sigma^2) over pixel positions, truncated at 3 sigma, zero outside the
// image: exactly symmetric, as the normalization assumes.
class SeparableGaussianKernel : public PairwiseKernel {
 public:
  void Prepare(cv::Size size, float sigma, float weight);
  void Apply(const float* in, float* out, int stride, bool accumulate, ThreadPool* pool) override;

  // Whether the separable blur is the cheaper filter for `channels` channels.
  static bool Preferred(float sigma, int channels);

 private:
  // dst = K src for an H x W image of `channels` floats per pixel.
  void Blur(const float* src, float* dst, int channels);

  cv::Size size_;
  cv::Mat taps_;
  float weight_ = 0.0f;
  std::vector<float> norm_;
  std::vector<float> scaled_;
  std::vector<float> blurred_;
};

}  // namespace moslam::semantic
