// Localization cues from class activation maps (Zhou et al. 2016), refined with superpixels and
// fused across the colour and grey classifiers: the modified cues of Sun, Tai, Gao, Liu, Yeung
// 2019 (following SEC's seeds, Kolesnikov and Lampert 2016).
//
// Cue maps are CV_8UC1: a class index, or kUnknown where no cue is given (those pixels do not
// enter the seeding loss).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "moslam/semantic/dense_crf.h"

namespace moslam::weak {

constexpr unsigned char kUnknown = 255;

struct CueOptions {
  // Foreground seeds: pixels where a present class's CAM, normalized by its maximum over the
  // image, is at least `foreground_threshold` and is the largest among present classes.
  float foreground_threshold = 0.5f;
  // Background seeds (only when the dataset has a background class): pixels where every present
  // class's normalized CAM is below `background_threshold`.
  float background_threshold = 0.15f;
  // SLIC superpixels (Achanta et al. 2012, OpenCV ximgproc): average side in pixels, compactness
  // (ruler) and iterations.
  int superpixel_size = 16;
  float superpixel_ruler = 10.0f;
  int superpixel_iterations = 10;
  // A superpixel takes a label (all its pixels) when at least `agreement` of its seeded pixels
  // carry that label and at least `min_coverage` of its pixels are seeded; otherwise its seeds are
  // dropped (superpixels straddling two labels are where seeds are least reliable). A high
  // coverage makes the refinement snap seeds to object boundaries: a blurry CAM's spill into a
  // neighbouring region covers only part of that region's superpixels, which are then dropped,
  // while superpixels inside the object are filled. A low coverage would instead grow every
  // superpixel the spill touches.
  float agreement = 0.8f;
  float min_coverage = 0.8f;

  void Check() const;  // InputError naming the field
};

// cams: {C, H, W} CV_32F class activation maps at the image's size (all classes of the
// classifier); present: the image-level labels; background: index of the background class or -1.
// Classes not present never receive seeds.
cv::Mat SeedsFromCams(const cv::Mat& cams, const std::vector<int>& present, int background,
                      const CueOptions& options);

// Crop-level suppression: `cell_classes` lists the classes of each of rows x cols equal cells of
// the image (row-major; augment.h's label grid), and every class's CAM in `cams` ({C, H, W}
// CV_32F) is set to 0 inside the cells that do not list it, so that SeedsFromCams neither seeds
// it there nor normalizes it by a maximum found there. Cell boundaries follow LabelSample's
// integer split (x0 = c * W / cols). With `per_cell_max`, a listed class's CAM is also ReLU'd and
// divided by its maximum within each cell, so that every cell that lists a class gets seeds of it
// (each cell is treated as the crop it was labelled as; otherwise the image's most salient
// instance sets the scale and fainter ones are never seeded). InputError when cell_classes does
// not have rows x cols lists.
void SuppressAbsentInCells(cv::Mat& cams, const std::vector<std::vector<int>>& cell_classes,
                           int rows, int cols, bool per_cell_max = false);

// Seeds equal to `label` inside the cells flagged in `cells` (rows x cols, row-major, the split of
// SuppressAbsentInCells) become kUnknown. InputError when cells does not have rows x cols flags.
void ClearLabelInCells(cv::Mat& seeds, const std::vector<bool>& cells, int rows, int cols,
                       int label);

// The labelled classes (`classes`, the background excepted) that `cue` seeds on fewer than
// `min_fraction` of its pixels: the classes a self-training cue missed.
std::vector<int> MissedClasses(const cv::Mat& cue, const std::vector<int>& classes, int background,
                               float min_fraction);

// Pixels where `source` (CV_8UC1 cue of any size, resized to the cue's by nearest neighbour) holds
// one of `classes` take that label in `cue`, whatever `cue` said there: a missed class's
// first-round seeds put back into a self-training cue, the rest of which is kept.
void FillClassesFrom(const cv::Mat& source, const std::vector<int>& classes, cv::Mat& cue);

// SLIC superpixel refinement of `seeds` on `image` (CV_8UC3 or CV_8UC1 of the seeds' size).
cv::Mat RefineWithSuperpixels(const cv::Mat& seeds, const cv::Mat& image,
                              const CueOptions& options);

// Fusion of the colour and grey cues: where both give a label and they agree, it is kept; where
// they disagree the pixel becomes kUnknown; where only one gives a label, it is kept.
// With `one_sided` false, only labels both cues agree on are kept (higher precision, fewer seeds).
cv::Mat FuseCues(const cv::Mat& colour, const cv::Mat& grey, bool one_sided = true);

// Cues of a second (self-training) round, from a trained segmentation network rather than from
// classifiers: its per-pixel class probabilities `probabilities` ({C, H, W} CV_32F at the image's
// size), with the classes absent from the image-level labels removed (`present`; `background`,
// when >= 0, is always kept), refined by `crf` on `image` (the fully connected CRF follows the
// image's edges where the network's upsampled output is blurry). A pixel takes the CRF's label
// when its marginal is at least `confidence`, else kUnknown. No pixel label is involved: the
// image-level labels and the image are all it uses, as in the first round.
// `depth_m` (CV_32F metres, the image's size, 0 = no reading) is required when the CRF has its
// depth kernel (DenseCrfOptions::depth), else ignored and may be empty.
cv::Mat CuesFromSegmentation(const cv::Mat& probabilities, const std::vector<int>& present,
                             int background, const cv::Mat& image, const cv::Mat& depth_m,
                             semantic::DenseCrf& crf, float confidence);

// Pseudo-colour rendering for inspection: each class a fixed colour, unknown black, blended over
// the image (CV_8UC3 output of the image's size).
cv::Mat RenderCue(const cv::Mat& cue, const cv::Mat& image);
// A CAM as a heat map over the image (JET colour map, CAM normalized by its maximum).
cv::Mat RenderCam(const cv::Mat& cam, const cv::Mat& image);

}  // namespace moslam::weak
