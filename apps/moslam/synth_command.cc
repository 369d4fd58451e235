// `moslam synth`: synthetic dynamic sequences with exact ground truth (docs/SYNTH.md).
//
//   moslam synth --preset w_xyz --seed 1 --out DIR [--frames K] [--textures DIR] [--motion-blur]
//   moslam synth --train N --seed S --out DIR [--textures-per-kind 4]
//   moslam synth --contact-sheet docs/synth_contact_sheet.png
//   moslam synth --list-presets
#include <string>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "commands.h"
#include "moslam/synth/check.h"
#include "moslam/synth/generator.h"
#include "moslam/util/error.h"

namespace moslam::app {
namespace {

struct SynthArgs {
  synth::GeneratorOptions options;
  int train = 0;
  std::string contact_sheet;
  bool list = false;
  bool exact = false;
  std::string people = "boxes";
  std::string check;
  int check_gap = 5;
};

void PrintStats(const synth::GenerateStats& s) {
  fmt::print("frames          {}\n", s.frames);
  fmt::print("time            {:.2f} s ({:.1f} frames/s, rendering and writing)\n", s.seconds,
             s.seconds > 0 ? s.frames / s.seconds : 0.0);
  fmt::print(
      "person pixels   mean {:.1f} %, max {:.1f} %, frames with 20-60 %: {:.1f} %, "
      "with > 10 %: {:.1f} %\n",
      100 * s.mean_person_fraction, 100 * s.max_person_fraction, 100 * s.frames_20_60,
      100 * s.frames_over_10);
  fmt::print("moving pixels   mean {:.1f} %\n", 100 * s.mean_moving_fraction);
}

void Run(SynthArgs& args) {
  if (args.list) {
    for (const auto& p : synth::Presets()) {
      fmt::print("{:<13} {:>5} frames at {:>4.1f} Hz  {}  {}\n", p.name, p.default_frames,
                 p.rate_hz, p.stereo ? "KITTI stereo" : "TUM RGB-D  ", p.description);
    }
    return;
  }
  if (!args.check.empty()) {
    const synth::ReprojectionStats s = synth::CheckReprojection(args.check, args.check_gap, 1, 4);
    fmt::print("re-projection of static pixels, frame i -> i + {} ({} depth)\n", args.check_gap,
               s.exact_depth ? "exact depth_gt/" : "noisy depth/");
    fmt::print("pixels checked  {} ({} occluded in the second frame)\n", s.checked, s.occluded);
    fmt::print("|dz| metres     median {:.5f}  p90 {:.5f}  p99 {:.5f}\n", s.depth_median,
               s.depth_p90, s.depth_p99);
    fmt::print("|dgrey| levels  median {:.2f}  p90 {:.2f}\n", s.grey_median, s.grey_p90);
    fmt::print("noisy depth within 3 sigma + quantization: {:.2f} %\n",
               100 * s.noisy_within_3sigma);
    return;
  }
  args.options.sensor_noise = !args.exact;
  args.options.people = synth::ParsePeopleStyle(args.people);
  if (!args.contact_sheet.empty()) {
    synth::WriteContactSheet(args.contact_sheet, args.options.seed, args.options.textures_dir, 4,
                             args.options.people);
    fmt::print("wrote {}\n", args.contact_sheet);
    return;
  }
  if (args.train > 0) {
    PrintStats(synth::GenerateTraining(args.options, args.train));
    return;
  }
  if (args.options.preset.empty()) {
    ThrowInput("synth: give --preset NAME, --train N, --contact-sheet PNG or --list-presets");
  }
  PrintStats(synth::GenerateSequence(args.options));
}

}  // namespace

void AddSynthCommand(CLI::App& app) {
  auto args = std::make_shared<SynthArgs>();
  auto* cmd = app.add_subcommand(
      "synth",
      "Render synthetic dynamic sequences (TUM RGB-D / KITTI layout) with exact ground "
      "truth, masks and labels");
  auto& o = args->options;
  cmd->add_option("--preset", o.preset, "Preset name (--list-presets)");
  cmd->add_option("--seed", o.seed, "Seed of scene, people, camera path, textures and noise")
      ->capture_default_str();
  cmd->add_option("--out", o.out, "Output folder");
  cmd->add_option("--frames", o.frames, "Frames to render (0: the preset's TUM-like length)")
      ->capture_default_str();
  cmd->add_option("--textures", o.textures_dir,
                  "Folder of photographs added to the built-in procedural textures");
  cmd->add_option("--textures-per-kind", o.textures_per_kind,
                  "Procedural textures of each kind (1-64; more: more varied training frames)")
      ->capture_default_str();
  cmd->add_flag("--motion-blur", o.motion_blur, "Blur colour over a 1/60 s exposure");
  cmd->add_option("--width", o.width, "Image width (0: the preset's)");
  cmd->add_option("--height", o.height, "Image height (0: the preset's)");
  cmd->add_option("--png-compression", o.png_compression, "zlib level of PNGs, 0-9")
      ->capture_default_str();
  cmd->add_flag("--exact", args->exact, "No sensor noise: exact depth and colour");
  cmd->add_option("--people", args->people,
                  "How people are drawn: boxes (the benchmark's figures) or bodies (skinned "
                  "meshes with faces, hair, clothes and a footprint-driven gait)")
      ->capture_default_str();
  cmd->add_option("--train", args->train,
                  "Training mode: this many independent frames (labels; masks under eval_only/)");
  cmd->add_option("--contact-sheet", args->contact_sheet,
                  "Write a PNG contact sheet of every preset (RGB, masks, depth) and exit");
  cmd->add_flag("--exact-depth", o.write_exact_depth,
                "Also write depth_gt/: exact depth for ground-truth checks");
  cmd->add_option("--check", args->check,
                  "Check a written RGB-D sequence: re-project static pixels with depth and poses");
  cmd->add_option("--check-gap", args->check_gap, "Frame gap of --check")->capture_default_str();
  cmd->add_flag("--list-presets", args->list, "List the presets and exit");
  cmd->callback([args] { Run(*args); });
}

}  // namespace moslam::app
