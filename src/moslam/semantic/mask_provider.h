// One interface for everything that turns a frame into a movable-object mask: networks run
// through OpenCV dnn (onnx_segmenter.h: per-pixel class scores; box_detector.h: boxes), and, in
// runner/, masks read from files and the synthetic generator's ground truth (adapted in
// runner/mask_source.h, since they need the frame's file names rather than its pixels).
//
// Work comes in two steps, so that a pipeline can run the network on frame k+1 while the CRF
// refines frame k: Predict() (pre-processing, the network, class probabilities at the working
// size) and Refine() (test-time suppression, CRF, upsampling, dilation; semantic/mask_refine.h).
// Segment() is both, timed. Predict() and Refine() may be called from two different threads, one
// thread each (the network and the refiner share no state); each keeps its buffers between frames.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/semantic/mask_refine.h"
#include "moslam/semantic/model_card.h"

namespace moslam::semantic {

struct MaskInput {
  cv::Mat image;  // CV_8UC3 (BGR), CV_8UC4 (BGRA) or CV_8UC1 (grey), the frame's size
  cv::Mat depth;  // CV_32FC1 metres of the image's size (0 = invalid); empty when there is none
};

// A detector's box, in image pixels.
struct Detection {
  int class_id = 0;  // index into the model card's classes
  float confidence = 0.0f;
  cv::Rect box;
};

struct MaskResult {
  cv::Mat mask;  // CV_8UC1 of the image's size: 255 = movable, 0 = static
  // Per-class probabilities {L, h, w} CV_32F at the working size and their argmax (h x w CV_8U),
  // classes in the order of the provider's class_names(); see RefineResult.
  cv::Mat probabilities;
  cv::Mat labels;
  std::vector<float> image_scores;    // per class: maximum probability over the image
  std::vector<int> suppressed;        // classes suppressed by test-time suppression
  std::vector<Detection> detections;  // detectors only: the kept boxes of every class
  double network_ms = 0.0;  // pre-processing, inference and turning outputs into probabilities
  double crf_ms = 0.0;      // the CRF, 0 without it
  double total_ms = 0.0;    // the whole Segment() call
};

// What the network made of a frame, before refinement.
struct Prediction {
  cv::Mat probabilities;              // {L, h, w} CV_32F at the working size, summing to 1
  std::vector<float> image_scores;    // per class, for suppression; empty: each plane's maximum
  std::vector<Detection> detections;  // detectors only: the kept boxes of every class
  double network_ms = 0.0;            // pre-processing, inference, probabilities
};

class MaskProvider {
 public:
  virtual ~MaskProvider() = default;
  // The network's part. InputError for an image of the wrong type, or a network output that does
  // not match the card.
  virtual Prediction Predict(const MaskInput& input) = 0;
  // The refinement of `prediction`, made by Predict(input) (the same frame). InputError when the
  // depth kernel needs a depth map that `input` lacks.
  virtual MaskResult Refine(Prediction prediction, const MaskInput& input) = 0;
  // Predict, then Refine, with total_ms.
  MaskResult Segment(const MaskInput& input);
  // The classes of MaskResult::probabilities, and which are movable.
  virtual const std::vector<std::string>& class_names() const = 0;
  virtual const std::vector<bool>& movable() const = 0;
  // For logs and summary.json, e.g. "onnx deeplabv3_mnv2_voc (movable: person, car), crf c".
  virtual std::string Describe() const = 0;
};

// MaskProvider::Refine of the network providers: `refiner` on the prediction's probabilities and
// image scores; the detections and network time are carried over.
MaskResult RefinePrediction(MaskRefiner& refiner, Prediction&& prediction, const MaskInput& input);

// The provider a card describes (ONNX segmentation or detector), with `refine` as its
// post-processing (usually card.refine with the command line's --crf and --mask-dilate).
// InputError for a torch card: those need libtorch, net::MakeAnyMaskProvider
// (net/torch_mask_provider.h) dispatches every kind.
std::unique_ptr<MaskProvider> MakeMaskProvider(const ModelCard& card, const RefineOptions& refine);

// The image as 8-bit BGR (grey replicated, alpha dropped); InputError for other types.
cv::Mat ToBgr(const cv::Mat& image);

}  // namespace moslam::semantic
