// Training loops of the weakly supervised pipeline (`moslam train classifier|cues|segmenter`):
//   1. TrainClassifier: multi-label classifier (sigmoid + binary cross-entropy on image-level
//      labels), once on colour and once on grey images;
//   2. GenerateCues: CAMs of both classifiers -> seeds -> superpixel refinement -> fusion;
//   3. TrainSegmenter: segmentation network with the seeding and constrain-to-boundary losses
//      (losses.h), plus the auxiliary image-level classifier used for test-time suppression.
// Every loop shows progress (loss, accuracy, images/s, ETA), writes a checkpoint after every epoch
// (resumable: the same command with `resume` continues from it), a training-curve PNG, a JSON
// report and inspectable images.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "moslam/net/networks.h"
#include "moslam/semantic/dense_crf.h"
#include "moslam/weak/augment.h"
#include "moslam/weak/cues.h"
#include "moslam/weak/image_list.h"

namespace moslam::weak {

// Class order of the segmentation network and of cue maps: the classifier's classes (the list's
// class_names) followed by the list's background class when it has one (synthetic data), so a
// seed's value is a classifier class index, or num_classes for background.
std::vector<std::string> SegmenterClasses(const ImageList& list);

// Where training images come from: exactly one of the three.
struct DataSource {
  std::string list;     // an image list (image_list.h); `classes` names its classes file
  std::string classes;  // classes file for `list`
  std::string camvid;   // CamVid root (ReadCamVid), with `split`
  std::string split = "train";
  std::string synthetic;  // a `moslam synth --train` folder
  // Synthetic data only: label crops and label-grid cells by what they contain, counted on the
  // generator's class images as CamVid's are on its label images (ReadSyntheticTraining).
  bool synthetic_crop_labels = false;
  // When not empty: only these classes are kept, all others merged into a "background" class
  // (KeepClasses), e.g. {Car, Pedestrian, Bicyclist} on CamVid.
  std::vector<std::string> keep_classes;

  void Check() const;  // InputError when none or several are set
  ImageList Load() const;
};

struct CommonTrainOptions {
  DataSource data;
  std::string out;  // output folder (created)
  int epochs = 20;
  int batch_size = 8;
  double learning_rate = 1e-3;  // Adam; the pretrained backbone gets backbone_lr_factor of it
  double backbone_lr_factor = 0.1;
  double weight_decay = 1e-5;
  uint64_t seed = 1;
  int threads = 2;         // at::set_num_threads
  bool resume = false;     // continue from out/checkpoint.mnet when it exists
  int max_images = 0;      // use only the first N images (0 = all): quick runs and tests
  int preview_images = 6;  // images rendered into out/preview/ after training
  AugmentOptions augment;

  void Check() const;
};

struct ClassifierTrainOptions {
  CommonTrainOptions common;
  net::NetConfig net;            // classes are filled from the data
  std::string imagenet_weights;  // empty: net::DefaultImageNetWeightsPath(); "none": random init
};

struct CueGenerationOptions {
  DataSource data;
  std::string colour_model;  // classifier model files; either may be empty (one cue only)
  std::string grey_model;
  // out/cues/<index>.png (CV_8U class indices of the segmenter's classes, kUnknown elsewhere, at
  // the image's size), out/cues.json (classes, options, statistics), out/preview/.
  std::string out;
  CueOptions cues;
  // Fusion keeps labels only one of the two cues gives (true) or only agreed labels (false).
  bool fuse_one_sided = true;
  int threads = 2;
  int max_images = 0;
  int preview_images = 12;
  // Optional: pixel-label folder used only to report the cues' precision (evaluation).
  std::string eval_labels;
  // Crop-level labels at cue time (both rounds; data with label images): the image is
  // divided into label_grid_cols x label_grid_rows equal cells, and a class absent from a cell's
  // labels (CropLabels' rule, the labels a crop of that cell would carry) gets no seed there, as
  // a class absent from the image gets none anywhere. 0 x 0: image-level labels only.
  int label_grid_cols = 0;
  int label_grid_rows = 0;
  // With a label grid (classifier cues): CAMs normalized by their maximum within each cell that
  // lists the class (SuppressAbsentInCells' per_cell_max), not over the whole image.
  bool cell_max = false;
  // With a label grid: no background seeds inside cells whose labels list a movable class (a
  // crop known to hold a car is where a stuff class's CAM most often spills over the car).
  bool no_background_in_movable_cells = false;
  // Self-training (a second round; replaces the classifiers when set): cues from a segmenter
  // trained on first-round cues, its softmax with the image-level labels' absent classes removed
  // and refined by `crf` (colour) at the cue size, kept where the CRF's marginal is at least
  // `confidence` (CuesFromSegmentation in cues.h). Its classes must be the data's.
  std::string segmenter_model;
  semantic::DenseCrfOptions crf;
  float confidence = 0.8f;
  // An image whose labels list a class the segmenter's cue does not seed (at least
  // `min_class_pixels` of its pixels) was missed by the segmenter, and its confident background
  // there would teach the next network to miss it too: such an image takes its cue from
  // `fallback_cues` (a cue folder of the same data, e.g. the first round's), or, without one, no
  // cue at all (every pixel kUnknown).
  std::string fallback_cues;
  float min_class_pixels = 0.001f;
  // Take from `fallback_cues` only the seeds of the classes the segmenter missed, written over its
  // cue (FillClassesFrom), rather than the whole fallback cue. A labelled object often covers
  // less than min_class_pixels of the image (CamVid labels a class present from 0.1 % of the
  // pixels), and replacing the whole cue then throws away every other class the segmenter found.
  // Best with no_background_in_movable_cells, so that the segmenter's background does not cover
  // the object it missed. Requires fallback_cues.
  bool fallback_per_class = false;
  // Self-training on RGB-D data: a folder of 16-bit depth PNGs named as the images (a `moslam
  // synth --train` folder's depth/), `depth_factor` raw units per metre. When set, the CRF gets
  // its depth kernel (crf.depth_* options; the paper's "c,d" with the colour kernel on): people
  // stand apart from the floor and walls in depth where colour may not separate them. Depth is
  // sensor data that comes with every image, not a label.
  std::string depth_folder;
  double depth_factor = 5000.0;
  // Test-time augmentation, in both rounds: the segmenter's softmax (self-training), or each
  // classifier's ReLU'd CAMs (internal::AugmentedCams), is the mean over the image resized by
  // each of `scales` (relative to the network's input size) and, with `flip`, over their mirror
  // images too, as WSSS methods do when they make pseudo-labels (e.g. Ahn and Kwak, CVPR 2018):
  // a larger scale finds small objects and outlines that the stride-16 map blurs, and averaging
  // cancels a part of the errors of any one view.
  std::vector<double> scales = {1.0};
  bool flip = false;
};

struct SegmenterTrainOptions {
  CommonTrainOptions common;
  net::NetConfig net;
  std::string cues;             // folder written by GenerateCues
  std::string init_classifier;  // backbone initialized from this classifier (else ImageNet)
  std::string imagenet_weights;
  double constrain_weight = 1.0;  // weight of the constrain-to-boundary loss
  // Resolution of both losses, as a stride in pixels of the network input; 0: the network's
  // output stride. A finer stride (e.g. 4) upsamples the logits bilinearly, as inference does,
  // before the losses: the cues keep more of their shape (DownsampleCues drops every cell that
  // straddles two labels, which at stride 16 is most of a person) and the CRF of the constrain loss
  // sees the image's edges at 4x the resolution, so the network learns logits whose upsampling
  // follows the boundaries.
  int loss_stride = 0;
  // Seeding loss weighting (SeedingLoss's balance, losses.h): 1 class-balanced as in SEC, 0 the
  // plain mean over seeds, between: a class's seeds weigh |S_c|^-seed_balance.
  double seed_balance = 1.0;
  double class_weight = 0.1;  // weight of the auxiliary image-level BCE
  // Probability that a training image is turned grey (replicated to three channels), so that one
  // network serves colour and grey cameras (KITTI odometry's cameras 0 and 1 are grey).
  double grey_probability = 0.3;
  // The CRF of the constrain loss, with its spatial standard deviations (sxy) in pixels of the
  // network input; they are divided by the output stride, since the CRF runs at the logits'
  // resolution (as SEC does).
  semantic::DenseCrfOptions crf;
};

struct TrainSummary {
  std::string model;  // path of the final model
  int epochs = 0;
  double final_loss = 0.0;
  double seconds = 0.0;
};

TrainSummary TrainClassifier(const ClassifierTrainOptions& options);
void GenerateCues(const CueGenerationOptions& options);
TrainSummary TrainSegmenter(const SegmenterTrainOptions& options);

}  // namespace moslam::weak
