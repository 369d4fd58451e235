// Data augmentation and batching for the weak pipeline: flip, scale, crop, colour (brightness,
// contrast, saturation), optional conversion to grey. The same geometric transform is applied to
// an optional cue map (nearest neighbour) so that segmentation training sees seeds aligned with
// the augmented image; crops of CamVid images are relabelled by what they contain (CropLabels).
#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include <torch/torch.h>
#include <opencv2/core.hpp>

#include "moslam/weak/image_list.h"

namespace moslam::weak {

struct AugmentOptions {
  int output_width = 320;  // pixels: every sample is resized to this
  int output_height = 240;
  bool flip = true;        // horizontal flip with probability 0.5
  double min_scale = 0.7;  // crop side as a fraction of the image side (uniform in range)
  double max_scale = 1.0;
  double crop_probability = 0.5;  // otherwise the whole image
  double brightness = 0.2;        // +- fraction
  double contrast = 0.2;          // +- fraction
  double saturation = 0.2;        // +- fraction (colour images)
  bool grey = false;              // convert to grey (replicated to three channels in tensors)
  // Crop-level labels of a grid of cells over each sample (0 x 0: none): entries with a label
  // image also get, for each of label_grid_cols x label_grid_rows equal cells of the sample, the
  // classes that cell contains (CropLabels' rule) — the labels a crop of that cell would have.
  // The classifier pools its CAMs over the same cells (TrainClassifier), so it learns at the
  // cells' scale without the image being cropped and enlarged.
  int label_grid_cols = 0;
  int label_grid_rows = 0;

  void Check() const;  // InputError naming the field
};

struct Sample {
  cv::Mat image;             // CV_8UC3 BGR (grey replicated when grey), output size
  cv::Mat cue;               // CV_8UC1 labels (255 = unknown) of output size, when a cue was given
  std::vector<int> classes;  // image-level labels of the (cropped) sample
  // With a label grid and a label image: the classes of each cell, row-major, in the sample's
  // (flipped) frame; empty otherwise.
  std::vector<std::vector<int>> cell_classes;
  int index = -1;  // entry index
};

// Reads entry `index` of `list` (and `cue_path` when not empty), augments it with `rng`.
// With `augment` false: the whole image resized, no flip or colour change (evaluation, cues); the
// grey conversion (options.grey) is the network's input type and applies either way. The random
// draws come in a fixed order (crop, flip, colour) from rng's raw output, so a seed gives the same
// samples on every platform. Labels of a crop: entries with a label_image are relabelled by
// CropLabels (list.label_min_fraction); others keep the whole image's labels — an approximation
// (a crop can cut an object away; min_scale bounds how much). Cues are resized with
// INTER_NEAREST_EXACT (pixel-centre aligned with the image's resampling). InputError naming the
// file for an unreadable image or a cue/label image that is not 8-bit single-channel of the
// image's size.
Sample LoadSample(const ImageList& list, int index, const AugmentOptions& options,
                  std::mt19937_64& rng, bool augment, const std::string& cue_path = "");

struct Batch {
  torch::Tensor images;  // N x 3 x H x W float, RGB in [-1, 1]
  torch::Tensor labels;  // N x C float multi-hot
  torch::Tensor cues;    // N x H x W int64 (255 = unknown), undefined without cues
  // N x C x rows x cols float multi-hot of the samples' cell_classes; undefined without them.
  torch::Tensor cell_labels;
  std::vector<cv::Mat> bgr;  // the samples' images (the CRF of the constrain loss needs them)
  std::vector<int> indices;
};

// InputError naming `what` and the first entry without a label image when `options` has a label
// grid: crop labels need label images (CamVid); LoadSample would give such entries no cell labels.
void RequireLabelImages(const ImageList& list, const AugmentOptions& options,
                        const std::string& what);

// `grid_rows` x `grid_cols` is the samples' label grid (0 x 0: none; every sample must then carry
// its cell labels).
Batch MakeBatch(const std::vector<Sample>& samples, int num_classes, int grid_rows = 0,
                int grid_cols = 0);

// BGR (or grey) 8-bit image -> 3 x H x W float tensor, RGB in [-1, 1].
torch::Tensor ToInputTensor(const cv::Mat& image);

}  // namespace moslam::weak
