// `moslam map`: what a run's map holds beyond its trajectory (issue 27, docs/RUNNING.md "Dense
// map").
//
//   moslam map export RUN_DIR [--out DIR] [--masks run|none|synth-gt|files DIR] [--resolution M]
//                     [--pixel-step N] [--max-depth M] [--mask-margin PX] [--no-ray-casting]
//                     [--score]
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "moslam/dense/export.h"
#include "moslam/util/error.h"

namespace moslam::app {
namespace {

struct MapExportArgs {
  std::string run_dir;
  std::string out;
  std::vector<std::string> masks = {"run"};
  dense::ExportOptions options;
  double max_depth = 0.0;
  bool no_ray_casting = false;
};

void SetMasks(const std::vector<std::string>& masks, dense::ExportOptions* options) {
  const std::string& kind = masks.at(0);
  const bool files = kind == "files";
  if (files != (masks.size() == 2)) {
    ThrowInput("--masks: 'files' takes a folder, the others none (run, none, synth-gt, files DIR)");
  }
  if (kind == "run") {
    options->masks = dense::ExportMasks::kRun;
  } else if (kind == "none") {
    options->masks = dense::ExportMasks::kNone;
  } else if (kind == "synth-gt" || files) {
    options->masks = dense::ExportMasks::kSource;
    options->mask_source.kind =
        files ? runner::MaskSourceKind::kFiles : runner::MaskSourceKind::kSynthGt;
    if (files) options->mask_source.folder = masks[1];
  } else {
    ThrowInput("--masks: unknown '{}' (run, none, synth-gt, files DIR)", kind);
  }
}

void RunExport(MapExportArgs args) {
  dense::ExportOptions& options = args.options;
  options.run_dir = args.run_dir;
  options.out = args.out;
  if (args.max_depth > 0.0) options.max_depth = args.max_depth;
  options.fusion.ray_casting = !args.no_ray_casting;
  SetMasks(args.masks, &options);
  const dense::ExportResult r = dense::ExportDenseMap(options);
  spdlog::info("map export: {} keyframes ({} with a mask), {} rays, {} masked pixels, {:.1f} s",
               r.keyframes, r.masked_frames, r.rays.rays, r.rays.masked, r.total_s);
  std::printf("%zu occupied voxels of %.3f m: %s, %s, %s\n", r.occupied, options.fusion.resolution,
              r.octree.c_str(), r.cloud.c_str(), r.picture.c_str());
  if (r.scores) {
    const dense::DenseMapScores& s = *r.scores;
    std::printf(
        "against the ground truth: %zu of %zu voxels where people were (%.3f %%); static scene "
        "seen by the keyframes: %zu voxels, %.1f %% occupied (%.1f %% within one voxel)\n",
        s.in_people, s.occupied, 100.0 * s.people_fraction, s.static_seen, 100.0 * s.completeness,
        100.0 * s.completeness_near);
  }
}

}  // namespace

void AddMapCommand(CLI::App& app) {
  CLI::App* map = app.add_subcommand("map", "What a run's map holds: dense export");
  map->require_subcommand(1);
  auto args = std::make_shared<MapExportArgs>();
  CLI::App* cmd = map->add_subcommand(
      "export",
      "Fuse the depth of a run's keyframes at their optimized poses into an OctoMap (map.bt), a "
      "coloured point cloud (map.ply) and a picture from above (map_top.png), leaving out the "
      "movable-object masks' pixels (RGB-D; stereo through semi-global matching)");
  cmd->add_option("run_dir", args->run_dir, "A `moslam run` output folder")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--out", args->out, "Output folder (default RUN_DIR/dense)");
  cmd->add_option("--masks", args->masks,
                  "run: the keyframe masks the run saved (moslam run --save-keyframe-masks); "
                  "none; synth-gt; files DIR")
      ->expected(1, 2)
      ->capture_default_str();
  cmd->add_option("--resolution", args->options.fusion.resolution, "Voxel edge, metres")
      ->capture_default_str();
  cmd->add_option("--pixel-step", args->options.fusion.pixel_step, "One ray per N x N pixels")
      ->capture_default_str();
  cmd->add_option("--max-depth", args->max_depth,
                  "Farthest depth fused, metres (default 4 for RGB-D, 30 for stereo)");
  cmd->add_option("--mask-margin", args->options.fusion.mask_margin_px,
                  "Grow the masks by this many pixels before leaving their pixels out")
      ->capture_default_str();
  cmd->add_flag("--no-ray-casting", args->no_ray_casting,
                "Mark only the depth's end points occupied; do not clear the voxels the rays pass");
  cmd->add_flag("--score", args->options.score,
                "Synthetic sequences: align the keyframes to the ground truth and score the map "
                "(voxels where people were, share of the static scene occupied; export.json)");
  cmd->callback([args] { RunExport(*args); });
}

}  // namespace moslam::app
