// From per-class scores to the binary movable-object mask tracking uses: the post-processing
// shared by every network-based mask provider (mask_provider.h).
//
//   1. the class probabilities are resized to a working resolution (the image's aspect ratio,
//      longest side `working_side`);
//   2. test-time suppression: a class whose highest probability anywhere in the image is below
//      `suppress_below` is taken to be absent and its probability moved to the others
//      (renormalized); weak, scattered responses of a class that is not in the picture are the
//      most common false positives of a segmentation network on another domain;
//   3. optionally a prior shift of the movable classes (`movable_bias`, below);
//   4. optionally the fully connected CRF (dense_crf.h) with the colour kernel (c), the depth
//      kernel (d) or both (cd), the paper's (Sun et al. 2019) three refinements;
//   5. the movable pixels (argmax is a movable class) are upsampled to the image's size
//      (bilinear on the 0/255 mask, thresholded at half, so edges are not blocky) and optionally
//      dilated.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/semantic/dense_crf.h"

namespace moslam {
class YamlFile;
}

namespace moslam::semantic {

// Which pairwise kernels the CRF uses besides smoothness; kNone skips the CRF.
enum class CrfMode { kNone, kColour, kDepth, kColourDepth };
const char* ToString(CrfMode mode);  // "none", "c", "d", "cd"
// "none", "c", "d", "cd" (also "c,d"); nullopt otherwise.
std::optional<CrfMode> ParseCrfMode(const std::string& text);

struct RefineOptions {
  CrfMode crf = CrfMode::kNone;
  // Longest side, in pixels, of the working resolution at which classes are compared and the CRF
  // runs (the image's aspect ratio is kept; never larger than the image). 0 = the image's size.
  // 320 because the CRF's cost grows with the pixels (anchors: 93 ms at 480x360 against 155 ms
  // at 640x480, two labels) while the mask only has to cover objects, not their fine edges.
  int working_side = 320;
  // Classes whose maximum probability over the image is below this are suppressed (0 = off).
  // The background class (ModelCard::background) is never suppressed.
  float suppress_below = 0.0f;
  // Run the CRF on two labels, static and movable (class probabilities summed), rather than on
  // every class: tracking only uses the mask, and the CRF's cost grows with the labels (anchors:
  // 93 ms for 2 labels against 192 ms for 21 at 480x360).
  bool crf_binary = true;
  // Added to the log-probability of every movable class before the decision and the CRF (the
  // probabilities are renormalized), in nats; 0 = off, negative = fewer movable pixels. A prior
  // correction (Saerens, Latinne, Decaestecker 2002, "Adjusting the outputs of a classifier to new
  // a priori probabilities"): a network trained with a class-balanced loss acts as if the rare
  // movable classes were as frequent as the background and over-predicts them. On two labels,
  // movable wins where its probability exceeds 1 / (1 + exp(movable_bias)). Choose it on
  // training images, never on the images you report.
  float movable_bias = 0.0f;
  int dilate_px = 0;  // grow the final mask by this many pixels (elliptic), >= 0
  // Its appearance/depth switches are set from `crf`; its spatial sigmas (sxy) are in pixels of
  // the full image and scaled to the working resolution.
  DenseCrfOptions crf_options;
  // InputError naming the field.
  void Check() const;
};

// Reads `prefix`working_side, suppress_below, crf_binary, movable_bias, dilate_px and the CRF's
// options under "crf." (dense_crf.h); absent keys keep their values.
void ReadRefineOptions(YamlFile& file, const std::string& prefix, RefineOptions* options);

// The working resolution for an image of `image_size` (see RefineOptions::working_side).
cv::Size WorkingSize(const cv::Size& image_size, int working_side);

// Planar {L, H, W} CV_32F helpers. Each plane resized to `size` with `interpolation`.
cv::Mat ResizePlanar(const cv::Mat& planar, const cv::Size& size, int interpolation);
// Softmax over the label axis, in place (numerically stable: the per-pixel maximum is removed).
void SoftmaxPlanar(cv::Mat* planar);
// Argmax over the label axis: H x W CV_8U (lowest label on ties).
cv::Mat ArgMaxPlanar(const cv::Mat& planar);
// The maximum of each plane.
std::vector<float> PlaneMaxima(const cv::Mat& planar);

// What refinement made of one frame.
struct RefineResult {
  cv::Mat probabilities;  // {L, h, w} at the working size, after suppression (after the CRF too
                          // when the CRF ran on every class)
  cv::Mat labels;         // h x w CV_8U argmax of `probabilities`
  cv::Mat mask;           // image size CV_8UC1, 255 = movable
  std::vector<float> image_scores;  // per class: its maximum probability over the image, or the
                                    // scores given to Refine
  std::vector<int> suppressed;      // classes suppressed in this frame
  double crf_ms = 0.0;              // time spent in the CRF (with its resizing)
};

class MaskRefiner {
 public:
  // `movable`: one flag per class; `background`: the class never suppressed (-1: none).
  // InputError for bad options.
  MaskRefiner(const RefineOptions& options, std::vector<bool> movable, int background);
  ~MaskRefiner();
  MaskRefiner(const MaskRefiner&) = delete;
  MaskRefiner& operator=(const MaskRefiner&) = delete;

  const RefineOptions& options() const { return options_; }

  // probabilities: {L, h, w} CV_32F, summing to 1 per pixel, at the working size (WorkingSize of
  // the image). image: 8UC1/8UC3/8UC4 of the frame; depth_m: CV_32F metres of the frame's size,
  // required by the depth kernel. InputError when the sizes or the class count disagree.
  // image_scores: per class, what test-time suppression compares with suppress_below (e.g. a
  // network's image-level class scores); empty = each class's maximum probability.
  RefineResult Refine(cv::Mat probabilities, const cv::Mat& image, const cv::Mat& depth_m,
                      const std::vector<float>& image_scores = {});

 private:
  // Multiplies the movable classes' planes by exp(movable_bias) and renormalizes in place.
  void ShiftMovablePrior(cv::Mat* probabilities) const;
  // The 0/255 movable mask at the working size; with the CRF on every class, *probabilities
  // becomes its marginals.
  cv::Mat MovableAtWorkingSize(cv::Mat* probabilities, const cv::Mat& labels, const cv::Mat& image,
                               const cv::Mat& depth_m, double* crf_ms);
  RefineOptions options_;
  std::vector<bool> movable_;
  int background_;
  // The CRF with its spatial sigmas scaled to the working resolution; rebuilt when the scale
  // changes (once per sequence in practice).
  DenseCrf& ScaledCrf(double scale);
  std::unique_ptr<DenseCrf> crf_;
  double crf_scale_ = 0.0;
};

}  // namespace moslam::semantic
