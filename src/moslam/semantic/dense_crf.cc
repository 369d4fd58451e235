#include "moslam/semantic/dense_crf.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <functional>
#include <utility>

#include "moslam/semantic/crf_kernels.h"
#include "moslam/semantic/fast_math.h"
#include "moslam/semantic/permutohedral_lattice.h"
#include "moslam/semantic/thread_pool.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

constexpr int kMaxLabels = 32;
// The mean-field update works on tiles of 4 pixels, one pixel per vector lane. Energies are
// stored tile by tile, label-major inside a tile (a vector per label).
constexpr int kTile = 4;

enum class KernelKind { kSmoothness, kAppearance, kDepth };

bool IsValidDepth(float z) { return std::isfinite(z) && z > 0.0f; }

// Feature rows of a bilateral kernel (see dense_crf.h), divided by their standard deviations,
// and for the depth kernel the pixels that take part (active stays empty otherwise).
int MakeFeatures(KernelKind kind, const cv::Mat& image, const cv::Mat& depth_m,
                 const DenseCrfOptions& o, std::vector<float>* features,
                 std::vector<uint8_t>* active) {
  const int rows = image.rows;
  const int cols = image.cols;
  const int channels = image.channels();
  int dim = 2;
  float sxy = o.smoothness_sxy;
  if (kind == KernelKind::kAppearance) {
    dim = 2 + channels;
    sxy = o.appearance_sxy;
  } else if (kind == KernelKind::kDepth) {
    dim = 3;
    sxy = o.depth_sxy;
  }
  features->resize(static_cast<size_t>(rows) * cols * dim);
  active->clear();
  if (kind == KernelKind::kDepth) active->resize(static_cast<size_t>(rows) * cols);
  const float inv_sxy = 1.0f / sxy;
  const float inv_srgb = 1.0f / o.appearance_srgb;
  const float inv_sd = 1.0f / o.depth_sd_m;
  float* f = features->data();
  for (int y = 0; y < rows; ++y) {
    const uint8_t* pixel = image.ptr<uint8_t>(y);
    const float* z = kind == KernelKind::kDepth ? depth_m.ptr<float>(y) : nullptr;
    for (int x = 0; x < cols; ++x, f += dim) {
      f[0] = static_cast<float>(x) * inv_sxy;
      f[1] = static_cast<float>(y) * inv_sxy;
      if (kind == KernelKind::kAppearance) {
        for (int c = 0; c < channels; ++c) {
          f[2 + c] = static_cast<float>(pixel[x * channels + c]) * inv_srgb;
        }
      } else if (kind == KernelKind::kDepth) {
        const bool valid = IsValidDepth(z[x]);
        (*active)[static_cast<size_t>(y) * cols + x] = valid ? 1 : 0;
        f[2] = valid ? z[x] * inv_sd : 0.0f;
      }
    }
  }
  return dim;
}

// Energies in tiles: tile t holds labels 0 .. L - 1 of pixels 4t .. 4t + 3, label-major; pixels
// past the end get 0. Probabilities become -log(clamped p). Throws on NaN/inf.
void ComputeEnergies(const Unaries& unaries, float min_probability, ThreadPool* pool,
                     std::vector<float>* energies) {
  const cv::Mat values = unaries.values.isContinuous() ? unaries.values : unaries.values.clone();
  const int labels = unaries.num_labels();
  const int64_t n = static_cast<int64_t>(unaries.size().area());
  const int64_t tiles = (n + kTile - 1) / kTile;
  const bool planar = values.dims == 3;
  const bool probabilities = unaries.kind == Unaries::Kind::kProbabilities;
  const float* src = values.ptr<float>();
  energies->resize(static_cast<size_t>(tiles) * labels * kTile);
  float* dst = energies->data();
  std::atomic<bool> finite{true};
  pool->ParallelFor(tiles, [&](int64_t begin, int64_t end) {
    I4 ok = I4{} == 0;
    for (int64_t t = begin; t < end; ++t) {
      const int64_t p0 = t * kTile;
      const bool full = p0 + kTile <= n;
      for (int l = 0; l < labels; ++l) {
        F4 v;
        if (planar && full) {
          v = Load4(src + l * n + p0);
        } else {
          for (int j = 0; j < kTile; ++j) {
            const int64_t p = p0 + j;
            v[j] = p >= n ? 1.0f : (planar ? src[l * n + p] : src[p * labels + l]);
          }
        }
        ok &= (v - v == 0.0f);  // false for NaN and infinities
        if (probabilities) {
          v = Select4(v < min_probability, Splat4(min_probability), v);
          v = Select4(v > 1.0f, Splat4(1.0f), v);
          v = -FastLog4(v);
        }
        for (int j = 0; j < kTile; ++j) v[j] = p0 + j < n ? v[j] : 0.0f;
        Store4(dst + (t * labels + l) * kTile, v);
      }
    }
    if (ok[0] == 0 || ok[1] == 0 || ok[2] == 0 || ok[3] == 0) finite = false;
  });
  if (!finite) ThrowInput("CRF unaries hold a value that is not finite (NaN or infinity)");
}

// One mean-field update for tiles [begin, end): from the energies and the message (null on the
// first, unary-only step) to Q for labels 0 .. L - 2 and, when `marginals` is set, all L planes
// and the argmax labels.
struct UpdateArgs {
  int labels = 0;
  int64_t num_pixels = 0;
  const float* energies = nullptr;
  const float* message = nullptr;
  const float* ones_message = nullptr;
  const float* compatibility = nullptr;  // null: Potts
  float* q = nullptr;
  float* marginals = nullptr;
  uint8_t* labels_out = nullptr;
};

// Rows of S floats of pixels p0 .. p0 + 3 (rows past `count` read as 0) -> one vector per
// channel, lanes = pixels.
template <int S>
void LoadTile(const float* rows, int64_t p0, int count, F4* channels) {
  if (count < kTile) {
    for (int s = 0; s < S; ++s) {
      for (int j = 0; j < kTile; ++j) channels[s][j] = j < count ? rows[(p0 + j) * S + s] : 0.0f;
    }
  } else if constexpr (S == 1) {
    channels[0] = Load4(rows + p0);
  } else if constexpr (S == 2) {
    const F4 x0 = Load4(rows + 2 * p0);
    const F4 x1 = Load4(rows + 2 * p0 + 4);
    channels[0] = __builtin_shufflevector(x0, x1, 0, 2, 4, 6);
    channels[1] = __builtin_shufflevector(x0, x1, 1, 3, 5, 7);
  } else {
    for (int g = 0; g < S; g += 4) {
      F4 r0 = Load4(rows + p0 * S + g);
      F4 r1 = Load4(rows + (p0 + 1) * S + g);
      F4 r2 = Load4(rows + (p0 + 2) * S + g);
      F4 r3 = Load4(rows + (p0 + 3) * S + g);
      Transpose4(r0, r1, r2, r3);
      channels[g] = r0;
      channels[g + 1] = r1;
      channels[g + 2] = r2;
      channels[g + 3] = r3;
    }
  }
}

// The inverse of LoadTile, writing only the first `count` rows.
template <int S>
void StoreTile(const F4* channels, int64_t p0, int count, float* rows) {
  if (count < kTile) {
    for (int s = 0; s < S; ++s) {
      for (int j = 0; j < count; ++j) rows[(p0 + j) * S + s] = channels[s][j];
    }
  } else if constexpr (S == 1) {
    Store4(rows + p0, channels[0]);
  } else if constexpr (S == 2) {
    Store4(rows + 2 * p0, __builtin_shufflevector(channels[0], channels[1], 0, 4, 1, 5));
    Store4(rows + 2 * p0 + 4, __builtin_shufflevector(channels[0], channels[1], 2, 6, 3, 7));
  } else {
    for (int g = 0; g < S; g += 4) {
      F4 r0 = channels[g];
      F4 r1 = channels[g + 1];
      F4 r2 = channels[g + 2];
      F4 r3 = channels[g + 3];
      Transpose4(r0, r1, r2, r3);
      Store4(rows + p0 * S + g, r0);
      Store4(rows + (p0 + 1) * S + g, r1);
      Store4(rows + (p0 + 2) * S + g, r2);
      Store4(rows + (p0 + 3) * S + g, r3);
    }
  }
}

template <int S>
void UpdateTiles(const UpdateArgs& u, int64_t begin, int64_t end) {
  const int labels = u.labels;
  const int last = labels - 1;  // the label that is not filtered
  F4 a[kMaxLabels];
  F4 m[kMaxLabels];
  for (int64_t t = begin; t < end; ++t) {
    const int64_t p0 = t * kTile;
    const int count = static_cast<int>(std::min<int64_t>(kTile, u.num_pixels - p0));
    const float* energies = u.energies + t * labels * kTile;
    for (int l = 0; l < labels; ++l) a[l] = -Load4(energies + l * kTile);
    if (u.message != nullptr) {
      // The message of labels 0 .. L - 2; the last label's follows from linearity and
      // sum_l Q(l) = 1: w K~ Q(L-1) = w K~ 1 - sum_l w K~ Q(l).
      LoadTile<S>(u.message, p0, count, m);
      F4 rest;
      LoadTile<1>(u.ones_message, p0, count, &rest);
      for (int l = 0; l < last; ++l) rest -= m[l];
      m[last] = rest;
      if (u.compatibility == nullptr) {
        // Potts: -sum_l' [l != l'] m(l') = m(l) - sum_l' m(l'), the sum being the same for all l.
        for (int l = 0; l < labels; ++l) a[l] += m[l];
      } else {
        for (int l = 0; l < labels; ++l) {
          for (int k = 0; k < labels; ++k) a[l] -= u.compatibility[l * labels + k] * m[k];
        }
      }
    }
    F4 top = a[0];
    for (int l = 1; l < labels; ++l) top = Max4(top, a[l]);
    F4 sum = Splat4(0.0f);
    for (int l = 0; l < labels; ++l) {
      a[l] = FastExp4(a[l] - top);
      sum += a[l];
    }
    const F4 inv = 1.0f / sum;
    for (int l = 0; l < labels; ++l) a[l] *= inv;
    // Q rows: labels 0 .. L - 2, then zero padding up to the stride.
    F4 q[S];
    for (int s = 0; s < S; ++s) q[s] = s < last ? a[s] : Splat4(0.0f);
    StoreTile<S>(q, p0, count, u.q);
    if (u.marginals != nullptr) {
      I4 best = I4{} * 0;
      F4 best_value = a[0];
      for (int l = 1; l < labels; ++l) {
        const I4 better = a[l] > best_value;
        best = (better & l) | (~better & best);
        best_value = Select4(better, a[l], best_value);
      }
      for (int j = 0; j < count; ++j) {
        for (int l = 0; l < labels; ++l) u.marginals[l * u.num_pixels + p0 + j] = a[l][j];
        u.labels_out[p0 + j] = static_cast<uint8_t>(best[j]);
      }
    }
  }
}

void UpdateTilesForStride(int stride, const UpdateArgs& u, int64_t begin, int64_t end) {
  switch (stride) {
    case 1:
      return UpdateTiles<1>(u, begin, end);
    case 2:
      return UpdateTiles<2>(u, begin, end);
    case 4:
      return UpdateTiles<4>(u, begin, end);
    case 8:
      return UpdateTiles<8>(u, begin, end);
    case 12:
      return UpdateTiles<12>(u, begin, end);
    case 16:
      return UpdateTiles<16>(u, begin, end);
    case 20:
      return UpdateTiles<20>(u, begin, end);
    case 24:
      return UpdateTiles<24>(u, begin, end);
    case 28:
      return UpdateTiles<28>(u, begin, end);
    case 32:
      return UpdateTiles<32>(u, begin, end);
    default:
      MOSLAM_CHECK(false) << "unsupported stride " << stride;
  }
}

void CheckInputs(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries,
                 const DenseCrfOptions& options) {
  if (image.empty()) ThrowInput("CRF: the image is empty");
  if (image.type() != CV_8UC3 && image.type() != CV_8UC1) {
    ThrowInput("CRF: the image must be 8-bit with 1 or 3 channels, got type {}", image.type());
  }
  if (unaries.values.depth() != CV_32F) ThrowInput("CRF: unaries must be CV_32F");
  const bool planar = unaries.values.dims == 3;
  if (!planar && (unaries.values.dims != 2 || unaries.values.channels() < 2)) {
    ThrowInput("CRF: unaries must be {{L, H, W}} planar or H x W with L channels");
  }
  if (planar && unaries.values.channels() != 1) {
    ThrowInput("CRF: planar unaries must have one channel");
  }
  const int labels = unaries.num_labels();
  if (labels < 2 || labels > kMaxLabels) {
    ThrowInput("CRF: {} labels; between 2 and {} are supported", labels, kMaxLabels);
  }
  const cv::Size size = unaries.size();
  if (size != image.size()) {
    ThrowInput("CRF: unaries are {}x{} but the image is {}x{}", size.width, size.height, image.cols,
               image.rows);
  }
  if (options.depth) {
    if (depth_m.empty()) ThrowInput("CRF: the depth kernel is enabled but no depth was given");
    if (depth_m.type() != CV_32FC1 || depth_m.size() != image.size()) {
      ThrowInput("CRF: depth must be CV_32F of the image's size ({}x{})", image.cols, image.rows);
    }
  }
  if (!options.compatibility.empty() &&
      options.compatibility.size() != static_cast<size_t>(labels) * labels) {
    ThrowInput("CRF: the compatibility matrix has {} entries but there are {} labels",
               options.compatibility.size(), labels);
  }
}

}  // namespace

struct DenseCrf::Workspace {
  std::vector<std::unique_ptr<PairwiseKernel>> kernels;
  std::vector<float> features;
  std::vector<uint8_t> active;
  std::vector<float> energies;      // tiles of 4 pixels x L labels (ComputeEnergies)
  std::vector<float> q;             // N x stride: Q for labels 0 .. L - 2
  std::vector<float> message;       // N x stride: sum_m w_m D^-1/2 K_m D^-1/2 Q
  std::vector<float> ones_message;  // N: sum_m w_m D^-1/2 K_m D^-1/2 1
  std::vector<float> compatibility;
};

DenseCrf::DenseCrf(const DenseCrfOptions& options)
    : options_(options), workspace_(std::make_unique<Workspace>()) {
  options_.Check();
  pool_ = std::make_unique<ThreadPool>(options_.num_threads);
}

DenseCrf::~DenseCrf() = default;

void DenseCrf::PrepareKernels(const cv::Mat& image, const cv::Mat& depth_m, int channels) {
  Workspace& w = *workspace_;
  const int n = static_cast<int>(image.total());
  w.kernels.clear();
  const auto add_lattice = [&](KernelKind kind, float weight) {
    const int dim = MakeFeatures(kind, image, depth_m, options_, &w.features, &w.active);
    auto kernel = std::make_unique<LatticeKernel>();
    kernel->Prepare(w.features.data(), n, dim, w.active.empty() ? nullptr : w.active.data(), weight,
                    pool_.get());
    w.kernels.push_back(std::move(kernel));
  };
  if (options_.smoothness) {
    const bool separable =
        options_.smoothness_filter == "separable" ||
        (options_.smoothness_filter == "auto" &&
         SeparableGaussianKernel::Preferred(options_.smoothness_sxy, channels));
    if (separable) {
      auto kernel = std::make_unique<SeparableGaussianKernel>();
      kernel->Prepare(image.size(), options_.smoothness_sxy, options_.smoothness_weight);
      w.kernels.push_back(std::move(kernel));
    } else {
      add_lattice(KernelKind::kSmoothness, options_.smoothness_weight);
    }
  }
  if (options_.appearance) add_lattice(KernelKind::kAppearance, options_.appearance_weight);
  if (options_.depth) add_lattice(KernelKind::kDepth, options_.depth_weight);
}

CrfResult DenseCrf::Infer(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries) {
  CheckInputs(image, depth_m, unaries, options_);
  const cv::Mat img = image.isContinuous() ? image : image.clone();
  Workspace& w = *workspace_;
  const int labels = unaries.num_labels();
  const int64_t n = static_cast<int64_t>(img.total());
  // Q and messages hold labels 0 .. L - 2 only (see UpdateTiles), padded to a lattice stride.
  const int stride = PermutohedralLattice::PaddedStride(labels - 1);

  ComputeEnergies(unaries, options_.min_probability, pool_.get(), &w.energies);
  PrepareKernels(img, depth_m, labels - 1);
  w.ones_message.assign(static_cast<size_t>(n), 0.0f);
  for (const auto& kernel : w.kernels) {
    const std::vector<float>& ones = kernel->filtered_ones();
    for (int64_t p = 0; p < n; ++p) w.ones_message[p] += ones[p];
  }
  w.compatibility.assign(options_.compatibility.begin(), options_.compatibility.end());
  w.q.assign(static_cast<size_t>(n) * stride, 0.0f);
  w.message.resize(static_cast<size_t>(n) * stride);

  CrfResult result;
  const int sizes[3] = {labels, img.rows, img.cols};
  result.marginals.create(3, sizes, CV_32F);
  result.labels.create(img.rows, img.cols, CV_8U);
  UpdateArgs u;
  u.labels = labels;
  u.num_pixels = n;
  u.energies = w.energies.data();
  u.ones_message = w.ones_message.data();
  u.compatibility = w.compatibility.empty() ? nullptr : w.compatibility.data();
  u.q = w.q.data();
  const int64_t tiles = (n + kTile - 1) / kTile;
  const auto update = [&](bool with_message, bool last) {
    u.message = with_message ? w.message.data() : nullptr;
    u.marginals = last ? result.marginals.ptr<float>() : nullptr;
    u.labels_out = last ? result.labels.ptr<uint8_t>() : nullptr;
    pool_->ParallelFor(
        tiles, [&](int64_t begin, int64_t end) { UpdateTilesForStride(stride, u, begin, end); });
  };

  const int iterations = w.kernels.empty() ? 0 : options_.iterations;
  update(false, iterations == 0);
  for (int it = 0; it < iterations; ++it) {
    for (size_t m = 0; m < w.kernels.size(); ++m) {
      w.kernels[m]->Apply(w.q.data(), w.message.data(), stride, m > 0, pool_.get());
    }
    update(true, it + 1 == iterations);
  }
  return result;
}

Unaries Unaries::FromProbabilities(cv::Mat probabilities) {
  return Unaries{Kind::kProbabilities, std::move(probabilities)};
}

Unaries Unaries::FromEnergies(cv::Mat energies) {
  return Unaries{Kind::kEnergies, std::move(energies)};
}

int Unaries::num_labels() const {
  if (values.dims == 3) return values.size[0];
  return values.empty() ? 0 : values.channels();
}

cv::Size Unaries::size() const {
  if (values.dims == 3) return cv::Size(values.size[2], values.size[1]);
  return values.size();
}

cv::Mat LabelPlane(const cv::Mat& planar, int label) {
  MOSLAM_CHECK_EQ(planar.dims, 3);
  MOSLAM_CHECK(label >= 0 && label < planar.size[0]) << "label " << label;
  return cv::Mat(planar.size[1], planar.size[2], planar.type(),
                 const_cast<uchar*>(planar.ptr(label)), planar.step[1]);
}

CrfResult InferDenseCrf(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries,
                        const DenseCrfOptions& options) {
  DenseCrf crf(options);
  return crf.Infer(image, depth_m, unaries);
}

}  // namespace moslam::semantic
