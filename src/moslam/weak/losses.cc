#include "moslam/weak/losses.h"

#include <algorithm>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "moslam/util/check.h"
#include "moslam/util/error.h"

namespace moslam::weak {

namespace {

constexpr int64_t kUnknownCue = 255;
// SEC's released code clamps probabilities at this value before taking logarithms.
constexpr double kMinProbability = 1e-5;

void RequireLogits(const torch::Tensor& logits, const char* function) {
  if (!logits.defined() || logits.dim() != 4 || logits.size(1) < 1) {
    ThrowInput("{}: logits must be N x C x h x w", function);
  }
  if (!logits.is_floating_point()) ThrowInput("{}: logits must be floating point", function);
}

}  // namespace

torch::Tensor SeedingLoss(const torch::Tensor& logits, const torch::Tensor& cues, double balance) {
  RequireLogits(logits, "SeedingLoss");
  if (!(balance >= 0.0 && balance <= 1.0)) {
    ThrowInput("SeedingLoss: balance must be in [0, 1], got {}", balance);
  }
  const int64_t num_classes = logits.size(1);
  if (!cues.defined() || cues.dim() != 3 || cues.size(0) != logits.size(0) ||
      cues.size(1) != logits.size(2) || cues.size(2) != logits.size(3)) {
    ThrowInput("SeedingLoss: cues must be N x h x w at the logits' resolution");
  }
  if (cues.scalar_type() != torch::kInt64) ThrowInput("SeedingLoss: cues must be int64");
  const torch::Tensor c = cues.to(logits.device());
  const torch::Tensor seeded = c != kUnknownCue;
  const torch::Tensor bad = seeded & ((c < 0) | (c >= num_classes));
  if (bad.any().item<bool>()) {
    ThrowInput("SeedingLoss: cue labels must be in [0, {}) or 255", num_classes);
  }
  if (!seeded.any().item<bool>()) {
    // Nothing seeded: a zero that still belongs to the graph, so that backward() works and every
    // parameter gets a (zero) gradient.
    return logits.sum() * 0.0;
  }
  // |S_c| over the batch, then each seeded pixel of class c weighs |S_c|^-b / sum_k |S_k|^(1-b);
  // with b = 1 that is 1 / (|C'| |S_c|), the balanced formula's two averages folded into one
  // weighted sum, and with b = 0 the plain mean.
  const torch::Tensor labels = torch::where(seeded, c, torch::zeros_like(c));
  const torch::Tensor counts =
      torch::bincount(c.masked_select(seeded), /*weights=*/{}, num_classes).to(logits.dtype());
  const torch::Tensor present = counts > 0;
  const torch::Tensor class_weight =
      torch::where(present, counts.clamp_min(1.0).pow(-balance), torch::zeros_like(counts));
  const torch::Tensor total = (class_weight * counts).sum();
  const torch::Tensor weights = seeded.to(logits.dtype()) *
                                class_weight.index_select(0, labels.flatten()).view_as(labels) /
                                total;
  const torch::Tensor log_probabilities =
      torch::log_softmax(logits, 1).gather(1, labels.unsqueeze(1)).squeeze(1);
  return -(weights.detach() * log_probabilities).sum();
}

torch::Tensor ConstrainLoss(const torch::Tensor& logits, const torch::Tensor& crf_marginals) {
  RequireLogits(logits, "ConstrainLoss");
  if (!crf_marginals.defined() || crf_marginals.sizes() != logits.sizes()) {
    ThrowInput("ConstrainLoss: crf_marginals must have the logits' shape");
  }
  const torch::Tensor q = crf_marginals.detach().to(logits.options());
  const torch::Tensor f = torch::softmax(logits, 1);
  // sum_c Q log(Q / f) with both clamped inside the logarithms; Q = 0 contributes 0.
  const torch::Tensor kl =
      (q * (q.clamp_min(kMinProbability).log() - f.clamp_min(kMinProbability).log())).sum(1);
  return kl.mean();
}

torch::Tensor CrfTargets(const torch::Tensor& logits, const std::vector<cv::Mat>& images,
                         semantic::DenseCrf& crf) {
  RequireLogits(logits, "CrfTargets");
  const int64_t n = logits.size(0);
  const int c = static_cast<int>(logits.size(1));
  const int h = static_cast<int>(logits.size(2));
  const int w = static_cast<int>(logits.size(3));
  if (static_cast<int64_t>(images.size()) != n) {
    ThrowInput("CrfTargets: {} images for a batch of {}", images.size(), n);
  }
  const torch::Tensor probabilities =
      torch::softmax(logits.detach(), 1).to(torch::kCPU, torch::kFloat32).contiguous();
  torch::Tensor targets = torch::empty({n, c, h, w}, torch::kFloat32);
  const int sizes[] = {c, h, w};
  semantic::CrfResult result;
  for (int64_t i = 0; i < n; ++i) {
    const cv::Mat& image = images[i];
    if (image.empty() || (image.type() != CV_8UC3 && image.type() != CV_8UC1)) {
      ThrowInput("CrfTargets: image {} must be CV_8UC3 or CV_8UC1", i);
    }
    cv::Mat small = image;
    // INTER_AREA averages the pixels of each output cell, as the logits' receptive grid does.
    if (image.size() != cv::Size(w, h))
      cv::resize(image, small, cv::Size(w, h), 0, 0, cv::INTER_AREA);
    // A planar {C, h, w} view of this image's probabilities (the CRF copies what it needs).
    const cv::Mat planar(3, sizes, CV_32F, probabilities[i].data_ptr<float>());
    crf.Infer(small, cv::Mat(), semantic::Unaries::FromProbabilities(planar), &result);
    MOSLAM_CHECK(result.marginals.dims == 3 && result.marginals.size[0] == c &&
                 result.marginals.isContinuous());
    const cv::Mat out(3, sizes, CV_32F, targets[i].data_ptr<float>());
    result.marginals.copyTo(out);
  }
  return targets.to(logits.device(), logits.scalar_type());
}

torch::Tensor DownsampleCues(const torch::Tensor& cues, int h, int w) {
  if (!cues.defined() || cues.dim() != 3 || cues.scalar_type() != torch::kInt64) {
    ThrowInput("DownsampleCues: cues must be N x H x W int64");
  }
  const int64_t n = cues.size(0);
  const int64_t rows = cues.size(1);
  const int64_t cols = cues.size(2);
  if (h < 1 || w < 1 || h > rows || w > cols) {
    ThrowInput("DownsampleCues: output {}x{} must be within 1x1 and the input's {}x{}", w, h, cols,
               rows);
  }
  const torch::Tensor in = cues.to(torch::kCPU).contiguous();
  torch::Tensor out = torch::full({n, h, w}, kUnknownCue, torch::kInt64);
  const auto a = in.accessor<int64_t, 3>();
  auto b = out.accessor<int64_t, 3>();
  for (int64_t i = 0; i < n; ++i) {
    for (int y = 0; y < h; ++y) {
      // Cell rows [y H / h, (y + 1) H / h): a partition of the input for any ratio.
      const int64_t y0 = y * rows / h;
      const int64_t y1 = (y + 1) * rows / h;
      for (int x = 0; x < w; ++x) {
        const int64_t x0 = x * cols / w;
        const int64_t x1 = (x + 1) * cols / w;
        int64_t label = kUnknownCue;
        int64_t seeded = 0;
        bool agree = true;
        for (int64_t v = y0; v < y1 && agree; ++v) {
          for (int64_t u = x0; u < x1; ++u) {
            const int64_t l = a[i][v][u];
            if (l == kUnknownCue) continue;
            if (seeded > 0 && l != label) {
              agree = false;
              break;
            }
            label = l;
            ++seeded;
          }
        }
        if (agree && 2 * seeded >= (y1 - y0) * (x1 - x0)) b[i][y][x] = label;
      }
    }
  }
  return out.to(cues.device());
}

}  // namespace moslam::weak
