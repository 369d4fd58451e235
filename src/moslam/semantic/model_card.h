// A model card: a small YAML file (OpenCV's dialect: the first line is %YAML:1.0) that says how to
// run a network with OpenCV dnn and what its outputs mean, so that any ONNX segmentation model or
// Darknet/ONNX detector can serve masks without code changes. Every key (an unknown one is an error
// naming it and the card):
//
//   type: segmentation          # segmentation (per-pixel class scores) | detector (boxes)
//   name: deeplabv3_mnv2_voc    # for logs and summaries (default: the card's file stem)
//   model: models/x/x.onnx      # ONNX file, or Darknet .weights; relative paths are tried
//                               # against the card's folder, then MOSLAM_SHARED (../shared)
//   config: models/x/x.cfg      # Darknet .cfg (detectors only; omit for ONNX)
//   input_width: 513            # network input, pixels (the image is resized to it)
//   input_height: 513
//   mean: [127.5, 127.5, 127.5] # subtracted per channel, in the network's channel order
//   scale: 0.00784313725        # multiplied after the mean: (x - mean) * scale
//   rgb: true                   # the network wants RGB (images are read as BGR)
//   classes: [background, ...]  # the network's classes in output order
//   movable: [person, car]      # classes whose pixels (or boxes) are movable objects
//   background: background      # segmentation: the class never suppressed (optional)
//   confidence: 0.25            # detector: minimum box confidence
//   nms: 0.45                   # detector: non-maximum suppression IoU
//   box_probability: 0.9        # detector: probability given to a box's class inside the box
//   threads: 2                  # torch: libtorch's intra-op threads (the CRF has crf.num_threads)
//   refine: {working_side: 320, suppress_below: 0.0, crf_binary: true, movable_bias: 0.0,
//            dilate_px: 0}              # RefineOptions (mask_refine.h)
//   crf: {...}                  # DenseCrfOptions fields (dense_crf.h)
//
// `type: torch` is a segmentation network of the weakly supervised pipeline run by libtorch
// (net/torch_mask_provider.h): `model` is its .mnet model file, which holds its own input size,
// normalization and classes (net/networks.h NetConfig). The keys input_width, input_height, mean,
// scale, rgb, classes, movable and background are then optional: absent ones are taken from the
// model file, given ones must agree with it (classes in the same order), except `movable`, which
// may choose other movable classes among the model's, and the input size, at which the provider
// runs the fully convolutional network instead of its training size. Such a card is completed when
// the provider loads the model (net::CompleteTorchCard); until then `classes` may be empty.
#pragma once

#include <string>
#include <vector>

#include "moslam/semantic/mask_refine.h"

namespace moslam::semantic {

enum class ModelKind { kSegmentation, kDetector, kTorch };
const char* ToString(ModelKind kind);  // "segmentation", "detector", "torch"

struct ModelCard {
  std::string path;  // the card file
  std::string name;
  ModelKind kind = ModelKind::kSegmentation;
  std::string model;   // resolved path of the weights
  std::string config;  // resolved path of a Darknet .cfg; empty otherwise
  int input_width = 0;
  int input_height = 0;
  std::vector<double> mean = {0.0, 0.0, 0.0};
  double scale = 1.0;
  bool rgb = true;
  std::vector<std::string> classes;
  std::vector<std::string> movable;
  std::string background;
  float confidence = 0.25f;
  float nms = 0.45f;
  float box_probability = 0.9f;
  // torch cards: libtorch's intra-op threads (at::set_num_threads, one pool per process). In
  // `moslam run` the network shares 2 cores with the CRF, tracking and mapping threads, where 1
  // can beat 2; alone (`moslam segment`, seg-eval) 2 is faster.
  int threads = 2;
  RefineOptions refine;

  // InputError naming the card and the key of the first bad value (e.g. a movable class that is
  // not among the classes). A torch card may leave the input size (0), classes and movable empty.
  void Check() const;
  // One flag per class: is it in `movable`.
  std::vector<bool> MovableFlags() const;
  // Index of `background` in `classes`, -1 when not set.
  int BackgroundIndex() const;
};

// MOSLAM_SHARED if set, else "../shared" (relative to the working directory).
std::string SharedRoot();

// Reads and checks a card; relative `model`/`config` paths are resolved against the card's
// folder, then `shared_root`; a file found in neither is an InputError naming the key, the card
// and both places tried.
ModelCard LoadModelCard(const std::string& path, const std::string& shared_root = SharedRoot());

// Replaces the movable classes (e.g. from --movable); InputError naming an unknown class.
void SetMovable(const std::vector<std::string>& names, ModelCard* card);

}  // namespace moslam::semantic
