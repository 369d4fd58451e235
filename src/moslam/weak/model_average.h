// Uniform weight averaging of segmentation networks: a "model soup" (Wortsman et al. 2022,
// "Model soups: averaging weights of multiple fine-tuned models improves accuracy without
// increasing inference time"). Networks fine-tuned from the same initialization (the same
// classifier and the same --seed, so the same random head) stay in one basin of the loss, and the
// average of their weights often predicts better than either, at the cost of one network: an
// ensemble of their outputs would double the inference time, which the 30 ms budget forbids.
// Averaging networks from different random heads is allowed but rarely useful (their channels
// are not aligned); the caller's evaluation decides.
#pragma once

#include <string>
#include <vector>

#include "moslam/net/networks.h"

namespace moslam::weak {

// The element-wise mean of every floating-point parameter and buffer of the segmenters in
// `paths` (integer buffers are taken from the first). InputError when fewer than two files are
// given, a file is not a segmenter model file, or the networks' configurations differ (the
// error names the file).
net::SegmenterNet AverageSegmenters(const std::vector<std::string>& paths);

struct AverageOptions {
  std::vector<std::string> models;  // segmenter model files (.mnet), at least two
  std::string out;                  // output folder: model.mnet and report.json
  bool half = true;                 // float16 weights, as the segmenter trainer writes them
  void Check() const;               // InputError naming the field
};

// Writes out/model.mnet (the average) and out/report.json (the inputs).
void AverageSegmenterFiles(const AverageOptions& options);

}  // namespace moslam::weak
