#include "moslam/semantic/crf_kernels.h"

#include <algorithm>
#include <cmath>

#include <opencv2/imgproc.hpp>

#include "moslam/semantic/thread_pool.h"
#include "moslam/util/check.h"

namespace moslam::semantic {
namespace {

void Run(ThreadPool* pool, int64_t n, const std::function<void(int64_t, int64_t)>& fn) {
  if (pool != nullptr) {
    pool->ParallelFor(n, fn);
  } else {
    fn(0, n);
  }
}

// A pixel's own contribution makes K 1 positive wherever the kernel applies; elsewhere (pixels
// left out of the depth kernel) the normalization is 0.
float InverseSqrtNorm(float k1) { return k1 > 0.0f ? 1.0f / std::sqrt(k1) : 0.0f; }

}  // namespace

void LatticeKernel::Prepare(const float* features, int num_pixels, int dim, const uint8_t* active,
                            float weight, ThreadPool* pool) {
  const auto n = static_cast<size_t>(num_pixels);
  lattice_.Build(features, num_pixels, dim, active, pool);
  ones_.assign(n, 1.0f);
  norm_.resize(n);
  slice_scale_.resize(n);
  filtered_ones_.resize(n);
  lattice_.Filter(ones_.data(), norm_.data(), 1, false, pool);
  for (size_t i = 0; i < n; ++i) {
    norm_[i] = InverseSqrtNorm(norm_[i]);
    slice_scale_[i] = weight * norm_[i];
  }
  // D^-1/2 on both sides and the weight on the slice side, folded into the lattice once.
  lattice_.ScaleWeights(norm_.data(), slice_scale_.data());
  lattice_.Filter(ones_.data(), filtered_ones_.data(), 1, false, pool);
}

void LatticeKernel::Apply(const float* in, float* out, int stride, bool accumulate,
                          ThreadPool* pool) {
  lattice_.Filter(in, out, stride, accumulate, pool);
}

bool SeparableGaussianKernel::Preferred(float sigma, int channels) {
  // Measured at 640x480, sigma 3: a lattice costs about 12 ms to build and 1.5 ms per channel
  // and iteration, the blur about 0.7 ms per channel and iteration and grows with sigma.
  return sigma <= 10.0f && channels <= 4;
}

void SeparableGaussianKernel::Prepare(cv::Size size, float sigma, float weight) {
  size_ = size;
  weight_ = weight;
  const int radius = static_cast<int>(std::ceil(3.0f * sigma));
  taps_ = cv::getGaussianKernel(2 * radius + 1, sigma, CV_32F);
  const auto n = static_cast<size_t>(size.area());
  const std::vector<float> ones(n, 1.0f);
  norm_.resize(n);
  Blur(ones.data(), norm_.data(), 1);
  for (float& v : norm_) v = InverseSqrtNorm(v);
  filtered_ones_.resize(n);
  Blur(norm_.data(), filtered_ones_.data(), 1);
  for (size_t i = 0; i < n; ++i) filtered_ones_[i] *= weight_ * norm_[i];
}

void SeparableGaussianKernel::Blur(const float* src, float* dst, int channels) {
  const cv::Mat in(size_, CV_32FC(channels), const_cast<float*>(src));
  cv::Mat out(size_, CV_32FC(channels), dst);
  cv::sepFilter2D(in, out, CV_32F, taps_, taps_, cv::Point(-1, -1), 0.0, cv::BORDER_CONSTANT);
  MOSLAM_CHECK(out.data == reinterpret_cast<uchar*>(dst)) << "sepFilter2D reallocated";
}

void SeparableGaussianKernel::Apply(const float* in, float* out, int stride, bool accumulate,
                                    ThreadPool* pool) {
  const int64_t n = size_.area();
  scaled_.resize(static_cast<size_t>(n) * stride);
  blurred_.resize(static_cast<size_t>(n) * stride);
  Run(pool, n, [&](int64_t begin, int64_t end) {
    for (int64_t p = begin; p < end; ++p) {
      for (int s = 0; s < stride; ++s) scaled_[p * stride + s] = in[p * stride + s] * norm_[p];
    }
  });
  Blur(scaled_.data(), blurred_.data(), stride);
  Run(pool, n, [&](int64_t begin, int64_t end) {
    for (int64_t p = begin; p < end; ++p) {
      const float scale = weight_ * norm_[p];
      for (int s = 0; s < stride; ++s) {
        const float v = blurred_[p * stride + s] * scale;
        out[p * stride + s] = accumulate ? out[p * stride + s] + v : v;
      }
    }
  });
}

}  // namespace moslam::semantic
