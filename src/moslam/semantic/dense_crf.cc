#include "moslam/semantic/dense_crf.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <utility>

#include <spdlog/spdlog.h>

#include "moslam/semantic/crf_kernels.h"
#include "moslam/semantic/crf_simd.h"
#include "moslam/semantic/permutohedral_lattice.h"
#include "moslam/semantic/thread_pool.h"
#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::semantic {
namespace {

constexpr int kMaxLabels = 32;
enum class KernelKind { kSmoothness, kAppearance, kDepth };

bool IsValidDepth(float z) { return std::isfinite(z) && z > 0.0f; }

// Feature rows of a bilateral kernel (see dense_crf.h), divided by their standard deviations,
// and for the depth kernel the pixels that take part (active stays empty otherwise).
int MakeFeatures(KernelKind kind, const cv::Mat& image, const cv::Mat& depth_m,
                 const DenseCrfOptions& o, ThreadPool* pool, std::vector<float>* features,
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
  pool->ParallelFor(rows, [&](int64_t begin, int64_t end) {
    for (int64_t y = begin; y < end; ++y) {
      const uint8_t* pixel = image.ptr<uint8_t>(static_cast<int>(y));
      const float* z =
          kind == KernelKind::kDepth ? depth_m.ptr<float>(static_cast<int>(y)) : nullptr;
      float* f = features->data() + y * cols * dim;
      for (int x = 0; x < cols; ++x, f += dim) {
        f[0] = static_cast<float>(x) * inv_sxy;
        f[1] = static_cast<float>(y) * inv_sxy;
        if (kind == KernelKind::kAppearance) {
          for (int c = 0; c < channels; ++c) {
            f[2 + c] = static_cast<float>(pixel[x * channels + c]) * inv_srgb;
          }
        } else if (kind == KernelKind::kDepth) {
          const bool valid = IsValidDepth(z[x]);
          (*active)[y * cols + x] = valid ? 1 : 0;
          f[2] = valid ? z[x] * inv_sd : 0.0f;
        }
      }
    }
  });
  return dim;
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
  // Kernel objects live as long as the DenseCrf so that their buffers are reused from image to
  // image (fresh allocations of this size cost page faults on every image); `kernels` lists the
  // ones in use for the current image.
  LatticeKernel lattices[3];  // indexed by KernelKind
  SeparableGaussianKernel separable;
  std::vector<PairwiseKernel*> kernels;
  std::vector<float> features;
  std::vector<uint8_t> active;
  std::vector<float> energies;      // tiles of pixels x L labels (crf_simd.h)
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
    const int dim =
        MakeFeatures(kind, image, depth_m, options_, pool_.get(), &w.features, &w.active);
    LatticeKernel& kernel = w.lattices[static_cast<int>(kind)];
    kernel.Prepare(w.features.data(), n, dim, w.active.empty() ? nullptr : w.active.data(), weight,
                   pool_.get());
    w.kernels.push_back(&kernel);
  };
  // A kernel of weight 0 changes nothing: skip it.
  if (options_.smoothness && options_.smoothness_weight > 0.0f) {
    const bool separable = options_.smoothness_filter == "separable" ||
                           (options_.smoothness_filter == "auto" &&
                            SeparableGaussianKernel::Preferred(options_.smoothness_sxy, channels));
    if (separable) {
      w.separable.Prepare(image.size(), options_.smoothness_sxy, options_.smoothness_weight);
      w.kernels.push_back(&w.separable);
    } else {
      add_lattice(KernelKind::kSmoothness, options_.smoothness_weight);
    }
  }
  if (options_.appearance && options_.appearance_weight > 0.0f) {
    add_lattice(KernelKind::kAppearance, options_.appearance_weight);
  }
  if (options_.depth && options_.depth_weight > 0.0f) {
    add_lattice(KernelKind::kDepth, options_.depth_weight);
  }
}

CrfResult DenseCrf::Infer(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries) {
  CrfResult result;
  Infer(image, depth_m, unaries, &result);
  return result;
}

void DenseCrf::Infer(const cv::Mat& image, const cv::Mat& depth_m, const Unaries& unaries,
                     CrfResult* result) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  CheckInputs(image, depth_m, unaries, options_);
  const cv::Mat img = image.isContinuous() ? image : image.clone();
  const cv::Mat values = unaries.values.isContinuous() ? unaries.values : unaries.values.clone();
  Workspace& w = *workspace_;
  const simd::Kernels& kernels = simd::Active();
  const int labels = unaries.num_labels();
  const int64_t n = static_cast<int64_t>(img.total());
  const int64_t tiles = (n + kernels.tile - 1) / kernels.tile;
  // Q and messages hold labels 0 .. L - 2 only (see UpdateTiles in crf_simd_impl.inc), padded
  // to a lattice stride.
  const int stride = PermutohedralLattice::PaddedStride(labels - 1);

  // Energies, and the first Q straight from them.
  simd::EnergyArgs e;
  e.labels = labels;
  e.num_pixels = n;
  e.values = values.ptr<float>();
  e.planar = values.dims == 3;
  e.probabilities = unaries.kind == Unaries::Kind::kProbabilities;
  e.min_probability = options_.min_probability;
  w.energies.resize(static_cast<size_t>(tiles) * kernels.tile * labels);
  w.q.resize(static_cast<size_t>(n) * stride);
  e.energies = w.energies.data();
  e.q = w.q.data();
  std::atomic<bool> finite{true};
  pool_->ParallelFor(tiles, [&](int64_t begin, int64_t end) {
    if (!kernels.energies(e, stride, begin, end)) finite = false;
  });
  if (!finite) ThrowInput("CRF unaries hold a value that is not finite (NaN or infinity)");
  const auto energies_done = Clock::now();

  PrepareKernels(img, depth_m, labels - 1);
  w.ones_message.assign(static_cast<size_t>(n), 0.0f);
  for (const PairwiseKernel* kernel : w.kernels) {
    const std::vector<float>& ones = kernel->filtered_ones();
    for (int64_t p = 0; p < n; ++p) w.ones_message[p] += ones[p];
  }
  w.compatibility.assign(options_.compatibility.begin(), options_.compatibility.end());
  w.message.resize(static_cast<size_t>(n) * stride);
  const auto kernels_done = Clock::now();

  const int sizes[3] = {labels, img.rows, img.cols};
  result->marginals.create(3, sizes, CV_32F);
  result->labels.create(img.rows, img.cols, CV_8U);
  simd::UpdateArgs u;
  u.labels = labels;
  u.num_pixels = n;
  u.energies = w.energies.data();
  u.ones_message = w.ones_message.data();
  u.compatibility = w.compatibility.empty() ? nullptr : w.compatibility.data();
  u.q = w.q.data();
  const auto update = [&](bool with_message, bool last) {
    u.message = with_message ? w.message.data() : nullptr;
    u.marginals = last ? result->marginals.ptr<float>() : nullptr;
    u.labels_out = last ? result->labels.ptr<uint8_t>() : nullptr;
    pool_->ParallelFor(tiles,
                       [&](int64_t begin, int64_t end) { kernels.update(u, stride, begin, end); });
  };
  // The energy pass gave the first Q; with no iterations the output is the normalized unaries.
  const int iterations = w.kernels.empty() ? 0 : options_.iterations;
  if (iterations == 0) update(false, true);
  for (int it = 0; it < iterations; ++it) {
    for (size_t m = 0; m < w.kernels.size(); ++m) {
      w.kernels[m]->Apply(w.q.data(), w.message.data(), stride, m > 0, pool_.get());
    }
    update(true, it + 1 == iterations);
  }
  const auto ms = [](Clock::duration d) {
    return std::chrono::duration<double, std::milli>(d).count();
  };
  spdlog::debug(
      "CRF {}x{}, {} labels, {} ({} threads): energies {:.1f} ms, kernels {:.1f} ms, "
      "{} iterations {:.1f} ms",
      img.cols, img.rows, labels, kernels.name, pool_->num_threads(), ms(energies_done - start),
      ms(kernels_done - energies_done), iterations, ms(Clock::now() - kernels_done));
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
