// `moslam train`: the weakly supervised segmentation pipeline (docs/WEAK.md), trained with
// image-level labels only.
//
//   moslam train classifier --camvid DIR | --synthetic DIR | --list FILE --classes FILE
//                           --out DIR [--grey] [--epochs 20] [--batch 8] [--lr 1e-3] ...
//   moslam train cues       <data> --colour-model M --grey-model M --out DIR [--eval-labels DIR]
//   moslam train segmenter  <data> --cues DIR --init-classifier M --out DIR [--epochs 20] ...
//   moslam train average    --models M1,M2[,...] --out DIR   (weight average of segmenters)
// Every training command resumes from DIR/checkpoint.mnet with --resume.
#include <string>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "moslam/util/error.h"
#include "moslam/weak/model_average.h"
#include "moslam/weak/training.h"

namespace moslam::app {
namespace {

void AddDataOptions(CLI::App* cmd, weak::DataSource* data) {
  cmd->add_option("--camvid", data->camvid, "CamVid root (train/, trainannot/, ...)");
  cmd->add_option("--split", data->split, "CamVid split")->capture_default_str();
  cmd->add_option("--synthetic", data->synthetic, "`moslam synth --train` output folder");
  cmd->add_flag("--synthetic-crop-labels", data->synthetic_crop_labels,
                "label crops and --label-grid cells of synthetic frames by what they contain "
                "(counted on the generator's eval_only/class images, as CamVid's crops are)");
  cmd->add_option("--list", data->list, "image list: `<image> <class> ...` per line");
  cmd->add_option("--classes", data->classes, "classes file for --list: `<id> <name> <movable>`");
  cmd->add_option("--keep-classes", data->keep_classes,
                  "train only these classes; all others become 'background'")
      ->delimiter(',');
}

void AddCommonOptions(CLI::App* cmd, weak::CommonTrainOptions* o) {
  AddDataOptions(cmd, &o->data);
  cmd->add_option("--out", o->out, "output folder")->required();
  cmd->add_option("--epochs", o->epochs, "epochs")->capture_default_str();
  cmd->add_option("--batch", o->batch_size, "images per batch")->capture_default_str();
  cmd->add_option("--lr", o->learning_rate, "Adam learning rate of new layers")
      ->capture_default_str();
  cmd->add_option("--backbone-lr-factor", o->backbone_lr_factor,
                  "learning rate factor of the pretrained backbone")
      ->capture_default_str();
  cmd->add_option("--weight-decay", o->weight_decay, "L2 weight decay")->capture_default_str();
  cmd->add_option("--seed", o->seed, "random seed")->capture_default_str();
  cmd->add_option("--threads", o->threads, "libtorch intra-op threads")->capture_default_str();
  cmd->add_flag("--resume", o->resume, "continue from OUT/checkpoint.mnet");
  cmd->add_option("--max-images", o->max_images, "use only the first N images (0: all)")
      ->capture_default_str();
  cmd->add_option("--preview", o->preview_images, "images rendered into OUT/preview")
      ->capture_default_str();
  cmd->add_option("--width", o->augment.output_width, "network input width, pixels")
      ->capture_default_str();
  cmd->add_option("--height", o->augment.output_height, "network input height, pixels")
      ->capture_default_str();
  cmd->add_option("--min-scale", o->augment.min_scale, "smallest random crop (fraction of side)")
      ->capture_default_str();
  cmd->add_option("--crop-probability", o->augment.crop_probability, "chance of a random crop")
      ->capture_default_str();
}

void AddBackboneOptions(CLI::App* cmd, net::NetConfig* net) {
  cmd->add_option("--last-block", net->backbone.last_block, "last MobileNetV2 block (1-18)")
      ->capture_default_str();
  cmd->add_option("--output-stride", net->backbone.output_stride, "8, 16 or 32")
      ->capture_default_str();
  cmd->add_option("--frozen-blocks", net->backbone.frozen_blocks, "blocks 0..N-1 are not trained")
      ->capture_default_str();
}

}  // namespace

void AddTrainCommand(CLI::App& app) {
  CLI::App* train = app.add_subcommand(
      "train", "Weakly supervised segmentation: classifiers, cues, segmentation network");
  train->require_subcommand(1);

  static weak::ClassifierTrainOptions classifier;
  CLI::App* c = train->add_subcommand("classifier", "multi-label classifier with CAMs");
  AddCommonOptions(c, &classifier.common);
  AddBackboneOptions(c, &classifier.net);
  c->add_flag("--grey", classifier.net.grey, "train on grey images");
  c->add_option("--label-grid-cols", classifier.common.augment.label_grid_cols,
                "crop labels of a grid of cells, columns (0: none; data with label images)")
      ->capture_default_str();
  c->add_option("--label-grid-rows", classifier.common.augment.label_grid_rows,
                "crop labels of a grid of cells, rows")
      ->capture_default_str();
  c->add_option("--imagenet", classifier.imagenet_weights,
                "ImageNet MobileNetV2 TorchScript file ('none': random init; default: shared)");
  c->callback([] { weak::TrainClassifier(classifier); });

  static weak::CueGenerationOptions cues;
  CLI::App* q = train->add_subcommand("cues", "seeds from CAMs, superpixels, colour+grey fusion");
  AddDataOptions(q, &cues.data);
  q->add_option("--colour-model", cues.colour_model, "colour classifier model file");
  q->add_option("--grey-model", cues.grey_model, "grey classifier model file");
  q->add_option("--out", cues.out, "output folder")->required();
  q->add_option("--foreground-threshold", cues.cues.foreground_threshold,
                "fraction of a CAM's maximum that seeds its class")
      ->capture_default_str();
  q->add_option("--background-threshold", cues.cues.background_threshold,
                "background seeds where every present CAM is below this fraction")
      ->capture_default_str();
  q->add_option("--superpixel-size", cues.cues.superpixel_size, "SLIC region size, pixels")
      ->capture_default_str();
  q->add_option("--agreement", cues.cues.agreement, "superpixel vote needed to keep a label")
      ->capture_default_str();
  q->add_option("--min-coverage", cues.cues.min_coverage,
                "fraction of a superpixel that must be seeded for it to keep a label")
      ->capture_default_str();
  q->add_flag("!--agreed-only", cues.fuse_one_sided,
              "fusion keeps only labels both classifiers agree on (default: also one-sided ones)");
  q->add_option("--threads", cues.threads, "libtorch intra-op threads")->capture_default_str();
  q->add_option("--max-images", cues.max_images, "first N images only (0: all)");
  q->add_option("--preview", cues.preview_images, "images rendered into OUT/preview")
      ->capture_default_str();
  q->add_option("--eval-labels", cues.eval_labels,
                "pixel-label folder, read only to report the cues' precision");
  q->add_option(
       "--label-grid-cols", cues.label_grid_cols,
       "crop labels of a grid of cells suppress absent classes per cell, columns (0: none)")
      ->capture_default_str();
  q->add_option("--label-grid-rows", cues.label_grid_rows, "crop-label grid rows")
      ->capture_default_str();
  q->add_flag("--cell-max", cues.cell_max,
              "with a label grid: normalize CAMs by their maximum in each cell, not the image");
  q->add_flag("--no-background-in-movable-cells", cues.no_background_in_movable_cells,
              "with a label grid: no background seeds in cells that hold a movable class");
  q->add_option("--segmenter", cues.segmenter_model,
                "self-training: cues from this segmenter + CRF instead of classifiers");
  q->add_option("--confidence", cues.confidence,
                "with --segmenter: CRF marginal a pixel needs to be seeded")
      ->capture_default_str();
  q->add_option("--fallback-cues", cues.fallback_cues,
                "with --segmenter: cue folder for images where the segmenter misses a labelled "
                "class (default: such images get no cues)");
  q->add_flag("--fallback-per-class", cues.fallback_per_class,
              "with --fallback-cues: only the missed classes' seeds are taken from it, over the "
              "segmenter's cue");
  q->add_option("--min-class-pixels", cues.min_class_pixels,
                "with --segmenter: fraction of an image a labelled class must be seeded on")
      ->capture_default_str();
  q->add_option("--depth-folder", cues.depth_folder,
                "with --segmenter: 16-bit depth PNGs named as the images (e.g. DATA/depth); the "
                "CRF adds its depth kernel");
  q->add_option("--depth-factor", cues.depth_factor, "raw depth units per metre")
      ->capture_default_str();
  q->add_option("--scales", cues.scales,
                "mean softmax (--segmenter) or CAMs (classifiers) over the image resized by "
                "these factors (e.g. 1,1.5,2)")
      ->delimiter(',')
      ->capture_default_str();
  q->add_flag("--flip", cues.flip, "also average the mirrored images");
  static std::string crf_config;
  q->add_option("--crf-config", crf_config,
                "with --segmenter: YAML file of crf.* options (default: the CRF's defaults)");
  q->callback([] {
    if (!crf_config.empty()) cues.crf = semantic::LoadDenseCrfOptions(crf_config);
    weak::GenerateCues(cues);
  });

  static weak::SegmenterTrainOptions segmenter;
  CLI::App* s = train->add_subcommand("segmenter", "segmentation network on the fused cues");
  AddCommonOptions(s, &segmenter.common);
  AddBackboneOptions(s, &segmenter.net);
  s->add_option("--cues", segmenter.cues, "folder written by `moslam train cues`")->required();
  s->add_option("--init-classifier", segmenter.init_classifier,
                "initialize the backbone from this classifier model");
  s->add_option("--imagenet", segmenter.imagenet_weights, "ImageNet weights when no classifier");
  s->add_option("--constrain-weight", segmenter.constrain_weight,
                "weight of the constrain-to-boundary loss")
      ->capture_default_str();
  s->add_option("--class-weight", segmenter.class_weight, "weight of the image-level BCE")
      ->capture_default_str();
  s->add_option("--grey-probability", segmenter.grey_probability,
                "chance that a training image is made grey")
      ->capture_default_str();
  s->add_option("--head-channels", segmenter.net.head_channels, "ASPP channels")
      ->capture_default_str();
  s->add_option("--decoder-block", segmenter.net.decoder_block,
                "DeepLabV3+ decoder on this backbone block's features (3: logits at stride 4; "
                "0: none)")
      ->capture_default_str();
  s->add_option("--decoder-channels", segmenter.net.decoder_channels, "decoder channels")
      ->capture_default_str();
  s->add_option("--loss-stride", segmenter.loss_stride,
                "losses on logits upsampled to input/N (0: the network's output stride)")
      ->capture_default_str();
  s->add_option("--seed-balance", segmenter.seed_balance,
                "seeding loss class balance: 1 per class as SEC, 0 the plain mean over seeds, "
                "between: a class's seeds weigh count^-B")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  s->add_flag_callback(
      "--unbalanced-seeds", [] { segmenter.seed_balance = 0.0; },
      "seeding loss as the plain mean over seeds (--seed-balance 0)");
  static std::string segmenter_crf_config;
  s->add_option("--crf-config", segmenter_crf_config,
                "YAML file of crf.* options for the constrain-to-boundary loss's CRF, sxy in "
                "input pixels (default: the CRF's defaults)");
  s->callback([] {
    if (!segmenter_crf_config.empty()) {
      segmenter.crf = semantic::LoadDenseCrfOptions(segmenter_crf_config);
    }
    weak::TrainSegmenter(segmenter);
  });

  static weak::AverageOptions average;
  CLI::App* a = train->add_subcommand(
      "average",
      "weight average of segmenters trained from the same classifier and --seed (a model soup: "
      "one network's inference time)");
  a->add_option("--models", average.models, "segmenter model files (.mnet), at least two")
      ->delimiter(',')
      ->required();
  a->add_option("--out", average.out, "output folder (model.mnet, report.json)")->required();
  a->add_flag("--half,!--float", average.half, "store float16 weights (as training does)")
      ->capture_default_str();
  a->callback([] { weak::AverageSegmenterFiles(average); });
}

}  // namespace moslam::app
