// Disparity error of the sparse stereo matcher (feature/stereo_matcher.h) against the synthetic
// generator's exact depth: developer measurement for issue 29 (docs/EVALUATION.md, "Stereo
// disparity bias").
//
//   stereo_bias --preset kitti_cars --seed 1 [--frames 20] [--step 10] [--no-noise]
//               [--subpixel parabola|equiangular] [--refine-level 0|keypoint]
//               [--max-ratio R]
//
// Renders frames 0, step, 2 step, ... of a stereo preset in-process (sensor noise as the written
// sequences have it unless --no-noise), extracts ORB features (2000, 1.2, 8 levels as
// configs/KITTI04-12.yaml) in both images, matches them with MatchStereo and compares each
// match's disparity with the ground truth bf / z at the keypoint. The ground truth is the inverse
// depth interpolated bilinearly (exact on planes) at the level-0 position of the keypoint's level
// pixel, (x_l + 0.5) * W / w_l - 0.5 (cv::resize's pixel centres), rounded to the pixel where the
// matcher centres its window when it refines on level 0; matches whose SAD window
// (11 x 11 level pixels) touches sky or a depth edge (inverse depth not planar there) are
// counted apart as "edge". Prints Markdown tables: error (estimate - truth, level-0 px) per
// octave and per true disparity range, with the relative depth error z_est / z_true - 1.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <opencv2/imgproc.hpp>

#include "moslam/feature/orb_extractor.h"
#include "moslam/feature/stereo_matcher.h"
#include "moslam/synth/generator.h"
#include "moslam/synth/presets.h"
#include "moslam/synth/renderer.h"
#include "moslam/synth/texture.h"
#include "moslam/util/error.h"
#include "moslam/util/log.h"

namespace {

using moslam::feature::OrbExtractor;
using moslam::feature::OrbExtractorOptions;
using moslam::feature::StereoMatchOptions;

struct Sample {
  int octave;
  double truth;     // level-0 px
  double estimate;  // level-0 px
  bool edge;        // the SAD window touches sky or a depth edge
};

// Inverse depth (0 on sky) and a mask of pixels where it is not locally planar.
struct Truth {
  cv::Mat inv_depth;  // CV_64F
  cv::Mat bad;        // CV_32S integral image of "sky or non-planar" pixels
};

Truth MakeTruth(const cv::Mat& depth_m) {
  Truth t;
  t.inv_depth = cv::Mat::zeros(depth_m.size(), CV_64F);
  cv::Mat bad = cv::Mat::zeros(depth_m.size(), CV_8U);
  for (int y = 0; y < depth_m.rows; ++y) {
    for (int x = 0; x < depth_m.cols; ++x) {
      const float z = depth_m.at<float>(y, x);
      if (z > 0.0f) t.inv_depth.at<double>(y, x) = 1.0 / z;
    }
  }
  // Planar surfaces have an affine inverse depth: its second differences vanish. A jump of more
  // than 0.2 % of the local inverse depth (or sky next to a surface) marks an edge.
  for (int y = 1; y + 1 < depth_m.rows; ++y) {
    for (int x = 1; x + 1 < depth_m.cols; ++x) {
      const double c = t.inv_depth.at<double>(y, x);
      if (c <= 0.0) {
        bad.at<uint8_t>(y, x) = 1;
        continue;
      }
      const double dxx =
          t.inv_depth.at<double>(y, x - 1) + t.inv_depth.at<double>(y, x + 1) - 2 * c;
      const double dyy =
          t.inv_depth.at<double>(y - 1, x) + t.inv_depth.at<double>(y + 1, x) - 2 * c;
      if (std::abs(dxx) > 2e-3 * c || std::abs(dyy) > 2e-3 * c) bad.at<uint8_t>(y, x) = 1;
    }
  }
  cv::integral(bad, t.bad, CV_32S);
  return t;
}

bool WindowBad(const Truth& t, double x, double y, double half) {
  const int x0 = std::max(0, static_cast<int>(std::floor(x - half)));
  const int y0 = std::max(0, static_cast<int>(std::floor(y - half)));
  const int x1 = std::min(t.bad.cols - 1, static_cast<int>(std::ceil(x + half)) + 1);
  const int y1 = std::min(t.bad.rows - 1, static_cast<int>(std::ceil(y + half)) + 1);
  const int sum =
      t.bad.at<int>(y1, x1) - t.bad.at<int>(y0, x1) - t.bad.at<int>(y1, x0) + t.bad.at<int>(y0, x0);
  return sum > 0;
}

double Bilinear(const cv::Mat& m, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= m.cols || y0 + 1 >= m.rows) return 0.0;
  const double ax = x - x0, ay = y - y0;
  return (1 - ay) * ((1 - ax) * m.at<double>(y0, x0) + ax * m.at<double>(y0, x0 + 1)) +
         ay * ((1 - ax) * m.at<double>(y0 + 1, x0) + ax * m.at<double>(y0 + 1, x0 + 1));
}

struct Stats {
  int n = 0, gross = 0;
  double mean = 0, sd = 0, median = 0, mad = 0, depth_mean = 0, depth_median = 0;
};

// Errors beyond 2 level pixels (2 * 1.2^octave level-0 px) are mismatches (wrong descriptor
// match, repeated texture), counted apart; the statistics are of the rest.
Stats Summarise(const std::vector<const Sample*>& s) {
  Stats st;
  std::vector<double> e, rel;
  for (const Sample* p : s) {
    const double err = p->estimate - p->truth;
    if (std::abs(err) > 2.0 * std::pow(1.2, p->octave)) {
      ++st.gross;
      continue;
    }
    e.push_back(err);
    rel.push_back(p->truth / p->estimate - 1.0);  // z_est / z_true - 1
  }
  st.n = static_cast<int>(e.size());
  if (e.empty()) return st;
  double sum = 0, sum2 = 0, rsum = 0;
  for (size_t i = 0; i < e.size(); ++i) {
    sum += e[i];
    sum2 += e[i] * e[i];
    rsum += rel[i];
  }
  st.mean = sum / st.n;
  st.sd = std::sqrt(std::max(0.0, sum2 / st.n - st.mean * st.mean));
  st.depth_mean = rsum / st.n;
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  st.median = median(e);
  std::vector<double> dev;
  for (double v : e) dev.push_back(std::abs(v - st.median));
  st.mad = 1.4826 * median(dev);
  st.depth_median = median(rel);
  return st;
}

void PrintRow(const std::string& name, const Stats& st) {
  const double gross = st.n + st.gross > 0 ? 100.0 * st.gross / (st.n + st.gross) : 0.0;
  std::printf("| %s | %d | %.1f | %+.4f | %.4f | %+.4f | %.4f | %+.3f | %+.3f |\n", name.c_str(),
              st.n, gross, st.mean, st.sd, st.median, st.mad, 100.0 * st.depth_mean,
              100.0 * st.depth_median);
}

void PrintTables(const std::vector<Sample>& samples, bool edges, double bf) {
  const char* header =
      "| %s | n | gross (%%) | mean err (px) | SD (px) | median err (px) | 1.48 MAD (px) | depth "
      "err mean (%%) | depth err median (%%) |\n|---|---|---|---|---|---|---|---|---|\n";
  std::printf("\n%s matches, per octave (error = estimate - truth, level-0 px):\n\n",
              edges ? "Edge" : "Interior");
  std::printf(header, "octave");
  std::vector<const Sample*> all;
  for (int o = 0; o < 8; ++o) {
    std::vector<const Sample*> s;
    for (const Sample& p : samples) {
      if (p.edge == edges && p.octave == o) s.push_back(&p);
    }
    all.insert(all.end(), s.begin(), s.end());
    if (!s.empty()) PrintRow(std::to_string(o), Summarise(s));
  }
  PrintRow("all", Summarise(all));
  std::printf("\n%s matches, per true depth (m):\n\n", edges ? "Edge" : "Interior");
  std::printf(header, "depth (disparity)");
  const double bounds[] = {0, 10, 20, 35, 45, 55, 75, 100, 150, 1e9};
  for (int b = 0; b + 1 < 10; ++b) {
    std::vector<const Sample*> s;
    for (const Sample& p : samples) {
      const double z = bf / p.truth;
      if (p.edge == edges && z >= bounds[b] && z < bounds[b + 1]) s.push_back(&p);
    }
    if (!s.empty()) {
      PrintRow(fmt::format("{}-{} m ({:.1f}-{:.1f} px)", bounds[b], bounds[b + 1],
                           bf / bounds[b + 1], bounds[b] > 0 ? bf / bounds[b] : 1e9),
               Summarise(s));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Disparity error of the stereo matcher against a synthetic preset's exact depth"};
  std::string preset = "kitti_cars", subpixel = "default", refine_level = "default";
  uint64_t seed = 1;
  int frames = 20, step = 10;
  bool no_noise = false;
  double max_ratio = -1.0;
  app.add_option("--preset", preset, "stereo preset (kitti_cars, open_road, ...)");
  app.add_option("--seed", seed, "preset seed");
  app.add_option("--frames", frames, "frames to measure")->check(CLI::PositiveNumber);
  app.add_option("--step", step, "frame step")->check(CLI::PositiveNumber);
  app.add_flag("--no-noise", no_noise, "render without colour noise");
  app.add_option("--subpixel", subpixel, "sub-pixel step: parabola or equiangular");
  app.add_option("--refine-level", refine_level, "SAD refinement on level 0 or keypoint");
  app.add_option("--max-ratio", max_ratio, "ambiguity ratio (second best / best SAD) threshold");
  CLI11_PARSE(app, argc, argv);
  try {
    StereoMatchOptions match;
    if (subpixel == "parabola") match.subpixel = moslam::feature::SubPixelFit::kParabola;
    if (subpixel == "equiangular") match.subpixel = moslam::feature::SubPixelFit::kEquiangular;
    if (refine_level == "0") match.refine_at_level0 = true;
    if (refine_level == "keypoint") match.refine_at_level0 = false;
    if (max_ratio >= 0.0) match.max_sad_ratio = max_ratio;
    match.Check();

    moslam::synth::GeneratorOptions go;
    go.preset = preset;
    go.seed = seed;
    go.sensor_noise = !no_noise;
    const moslam::synth::TextureSet textures =
        moslam::synth::TextureSet::Procedural(seed, go.textures_per_kind, go.texture_size);
    const moslam::synth::SequenceSpec spec = moslam::synth::MakePreset(preset, seed, textures);
    if (!spec.info.stereo) moslam::ThrowInput("preset {} is not stereo", preset);
    moslam::synth::Renderer renderer(spec.camera.width, spec.camera.height, textures);
    const double bf = spec.baseline_m * spec.camera.fx;
    OrbExtractorOptions eo;
    eo.num_features = 2000;
    std::vector<Sample> samples;
    for (int k = 0; k < frames; ++k) {
      const moslam::synth::FrameData f = RenderFrame(spec, renderer, k * step, go);
      cv::Mat left, right;
      cv::cvtColor(f.rgb, left, cv::COLOR_RGB2GRAY);
      cv::cvtColor(f.right, right, cv::COLOR_RGB2GRAY);
      OrbExtractor le(eo), re(eo);
      const auto lf = le.Extract(left);
      const auto rf = re.Extract(right);
      const auto m = MatchStereo(lf, le, rf, re, bf, spec.camera.fx, match);
      const Truth truth = MakeTruth(f.depth_m);
      for (size_t i = 0; i < lf.keypoints.size(); ++i) {
        if (m.right_index[i] < 0) continue;
        const cv::KeyPoint& kp = lf.keypoints[i];
        const int o = kp.octave;
        const cv::Mat& level = le.level_image(o);
        const double sx = static_cast<double>(left.cols) / level.cols;
        const double sy = static_cast<double>(left.rows) / level.rows;
        const double xl = std::round(kp.pt.x * le.inv_scale_factors()[o]);
        const double yl = std::round(kp.pt.y * le.inv_scale_factors()[o]);
        double x0 = (xl + 0.5) * sx - 0.5, y0 = (yl + 0.5) * sy - 0.5;
        if (match.refine_at_level0) {  // the matcher's window centre: the nearest level-0 pixel
          x0 = std::round(x0);
          y0 = std::round(y0);
        }
        const double inv_z = Bilinear(truth.inv_depth, x0, y0);
        Sample s;
        s.octave = o;
        s.truth = inv_z > 0.0 ? bf * inv_z : 0.0;
        s.estimate = kp.pt.x - m.u_right[i];
        s.edge = inv_z <= 0.0 || WindowBad(truth, x0, y0, 6.0 * sx);
        if (s.truth > 0.0) samples.push_back(s);
      }
    }
    std::printf("preset %s seed %llu, frames %d (step %d), noise %s, bf %.3f, %zu matches\n",
                preset.c_str(), static_cast<unsigned long long>(seed), frames, step,
                no_noise ? "off" : "on", bf, samples.size());
    PrintTables(samples, false, bf);
    PrintTables(samples, true, bf);
  } catch (const moslam::InputError& e) {
    std::fprintf(stderr, "stereo_bias: %s\n", e.what());
    return 1;
  }
  return 0;
}
