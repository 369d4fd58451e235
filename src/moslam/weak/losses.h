// The losses of SEC (A. Kolesnikov, C. H. Lampert, "Seed, expand and constrain", ECCV 2016) as
// used by Sun et al. 2019 for the segmentation network:
//   seeding loss: cross-entropy at seeded pixels only, class-balanced,
//     L_seed = -1/|C'| sum_{c in C'} 1/|S_c| sum_{u in S_c} log f_{u,c}(X)
//     with S_c the pixels seeded with c and C' the classes with at least one seed (per batch);
//   constrain-to-boundary loss: KL divergence between the dense-CRF-refined output Q and the
//     network output f, averaged over pixels,
//     L_constrain = 1/n sum_u sum_c Q_{u,c} log(Q_{u,c} / f_{u,c}(X)),
//     where Q = CRF(f(X), image) is a constant (no gradient flows through the CRF).
#pragma once

#include <vector>

#include <torch/torch.h>
#include <opencv2/core.hpp>

#include "moslam/semantic/dense_crf.h"

namespace moslam::weak {

// logits: N x C x h x w; cues: N x h x w int64 with kUnknown (255) where unseeded. Cues must be
// at the logits' resolution (see DownsampleCues). Returns 0 (with a graph) when nothing is seeded.
// `balance` in [0, 1] sets how the seeds of the batch's classes are weighed: a seed of class c
// weighs |S_c|^-balance / sum_k |S_k|^(1 - balance) (|S_c|: seeds of class c in the batch; the
// weights sum to 1). 1 is SEC's class-balanced form (each present class weighs 1 / |C'| in all),
// 0 the plain mean over seeds. The balanced form weighs a rare class's seeds up, which biases the
// network towards that class where the seeds say nothing (a person class seeded on 7 % of pixels
// weighs ~10x the background; CamVid's bicyclists, on 0.3 %, ~300x); values between temper it.
torch::Tensor SeedingLoss(const torch::Tensor& logits, const torch::Tensor& cues,
                          double balance = 1.0);

// logits: N x C x h x w; crf_marginals: N x C x h x w probabilities (constant). Both at the same
// resolution. Probabilities are clamped below at 1e-5 inside the logarithms.
torch::Tensor ConstrainLoss(const torch::Tensor& logits, const torch::Tensor& crf_marginals);

// The CRF targets of ConstrainLoss: softmax(logits) (detached) refined by `crf` on each image
// (CV_8UC3 or CV_8UC1, resized to the logits' h x w with INTER_AREA). Returns N x C x h x w.
torch::Tensor CrfTargets(const torch::Tensor& logits, const std::vector<cv::Mat>& images,
                         semantic::DenseCrf& crf);

// Cue maps (N x H x W int64, kUnknown = 255) at a lower resolution h x w: a low-resolution pixel
// takes a label when every seeded input pixel in its cell agrees and at least half of the cell is
// seeded; otherwise kUnknown.
torch::Tensor DownsampleCues(const torch::Tensor& cues, int h, int w);

}  // namespace moslam::weak
