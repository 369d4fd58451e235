// Disparity error of the stereo matcher against a synthetic preset's exact depth: developer
// measurement for issue 29 (docs/EVALUATION.md, "Stereo disparity bias"; stereo_error.h says how).
//
//   stereo_bias --preset kitti_cars --seed 1 [--frames 20] [--step 10] [--no-noise]
//               [--subpixel parabola|equiangular] [--refine-level 0|keypoint] [--max-ratio R]
//
// Prints Markdown tables: the error (estimate - truth, level-0 px) per octave and per true depth,
// with the relative depth error z_est / z_true - 1, for interior and edge matches apart.
#include <cstdio>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "moslam/util/error.h"
#include "stereo_error.h"

namespace {

using moslam::tools::StereoSample;

void PrintTables(const std::vector<StereoSample>& samples, bool edges, double bf) {
  std::vector<const StereoSample*> selected;
  for (const StereoSample& p : samples) {
    if (p.edge == edges) selected.push_back(&p);
  }
  // Depth bins in metres: ORB-SLAM2's stereo range on KITTI and beyond.
  moslam::tools::PrintErrorTables(selected, edges ? "Edge matches" : "Interior matches", bf,
                                  {0, 10, 20, 35, 45, 55, 75, 100, 150});
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Disparity error of the stereo matcher against a synthetic preset's exact depth"};
  moslam::tools::StereoErrorOptions o;
  std::string subpixel = "default", refine_level = "default";
  bool no_noise = false;
  double max_ratio = -1.0;
  std::string dump;
  int max_half = -1;
  app.add_option("--preset", o.preset, "stereo preset (kitti_cars, open_road, ...)");
  app.add_option("--seed", o.seed, "preset seed");
  app.add_option("--frames", o.frames, "frames to measure")->check(CLI::PositiveNumber);
  app.add_option("--step", o.step, "frame step")->check(CLI::PositiveNumber);
  app.add_flag("--no-noise", no_noise, "render without colour noise");
  app.add_option("--subpixel", subpixel, "sub-pixel fit: parabola or equiangular")
      ->check(CLI::IsMember({"default", "parabola", "equiangular"}));
  app.add_option("--refine-level", refine_level, "sub-pixel step on level 0 or the keypoint's")
      ->check(CLI::IsMember({"default", "0", "keypoint"}));
  app.add_option("--max-ratio", max_ratio, "ambiguity test: largest best / second-best SAD");
  app.add_option("--dump", dump, "CSV of every sample: frame,octave,x,y,truth,estimate,edge");
  app.add_option("--level0-max-half", max_half, "largest half-size of the level-0 window");
  CLI11_PARSE(app, argc, argv);
  try {
    o.noise = !no_noise;
    if (subpixel == "parabola") o.match.subpixel = moslam::feature::SubPixelFit::kParabola;
    if (subpixel == "equiangular") o.match.subpixel = moslam::feature::SubPixelFit::kEquiangular;
    if (refine_level != "default") o.match.refine_at_level0 = refine_level == "0";
    if (max_half > 0) o.match.level0_max_half_size = max_half;
    if (max_ratio >= 0.0) o.match.max_sad_ratio = max_ratio;
    const moslam::tools::StereoErrorResult r = MeasureStereoError(o);
    std::printf("preset %s seed %llu, frames %d (step %d), noise %s, bf %.3f, %zu matches\n",
                o.preset.c_str(), static_cast<unsigned long long>(o.seed), o.frames, o.step,
                o.noise ? "on" : "off", r.bf, r.samples.size());
    if (!dump.empty()) {
      std::FILE* f = std::fopen(dump.c_str(), "w");
      if (f == nullptr) moslam::ThrowInput("stereo_bias: cannot write {}", dump);
      std::fprintf(f, "frame,octave,x,y,truth,estimate,edge\n");
      for (const StereoSample& s : r.samples) {
        std::fprintf(f, "%d,%d,%.1f,%.1f,%.5f,%.5f,%d\n", s.frame, s.octave, s.x, s.y, s.truth,
                     s.estimate, s.edge ? 1 : 0);
      }
      std::fclose(f);
    }
    PrintTables(r.samples, false, r.bf);
    PrintTables(r.samples, true, r.bf);
  } catch (const moslam::InputError& e) {
    std::fprintf(stderr, "stereo_bias: %s\n", e.what());
    return 1;
  }
  return 0;
}
