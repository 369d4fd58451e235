#include "stereo_error.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <fmt/format.h>

#include <opencv2/imgproc.hpp>

#include "moslam/feature/orb_extractor.h"
#include "moslam/synth/generator.h"
#include "moslam/synth/presets.h"
#include "moslam/synth/renderer.h"
#include "moslam/synth/texture.h"
#include "moslam/util/error.h"

namespace moslam::tools {
namespace {

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

// The samples of one rendered frame.
void MeasureFrame(const synth::FrameData& f, double bf, double fx,
                  const feature::StereoMatchOptions& match, std::vector<StereoSample>* out) {
  cv::Mat left, right;
  cv::cvtColor(f.rgb, left, cv::COLOR_RGB2GRAY);
  cv::cvtColor(f.right, right, cv::COLOR_RGB2GRAY);
  feature::OrbExtractorOptions eo;
  eo.num_features = 2000;
  feature::OrbExtractor le(eo), re(eo);
  const auto lf = le.Extract(left);
  const auto rf = re.Extract(right);
  const auto m = MatchStereo(lf, le, rf, re, bf, fx, match);
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
    if (match.refine_at_level0) {
      x0 = std::round(x0);
      y0 = std::round(y0);
    }
    const double inv_z = Bilinear(truth.inv_depth, x0, y0);
    if (!(inv_z > 0.0)) continue;
    StereoSample s;
    s.octave = o;
    s.truth = bf * inv_z;
    s.estimate = kp.pt.x - m.u_right[i];
    s.edge = WindowBad(truth, x0, y0, (match.patch_half_size + 1) * sx);
    s.x = static_cast<float>(x0);
    s.y = static_cast<float>(y0);
    out->push_back(s);
  }
}

}  // namespace

StereoErrorResult MeasureStereoError(const StereoErrorOptions& options) {
  options.match.Check();
  synth::GeneratorOptions go;
  go.preset = options.preset;
  go.seed = options.seed;
  go.sensor_noise = options.noise;
  const synth::TextureSet textures =
      synth::TextureSet::Procedural(options.seed, go.textures_per_kind, go.texture_size);
  const synth::SequenceSpec spec = synth::MakePreset(options.preset, options.seed, textures);
  if (!spec.info.stereo) ThrowInput("stereo_bias: preset {} is not stereo", options.preset);
  synth::Renderer renderer(spec.camera.width, spec.camera.height, textures);
  StereoErrorResult result;
  result.bf = spec.baseline_m * spec.camera.fx;
  for (int k = 0; k < options.frames; ++k) {
    const synth::FrameData f = RenderFrame(spec, renderer, k * options.step, go);
    const size_t first = result.samples.size();
    MeasureFrame(f, result.bf, spec.camera.fx, options.match, &result.samples);
    for (size_t i = first; i < result.samples.size(); ++i)
      result.samples[i].frame = k * options.step;
  }
  return result;
}

ErrorStats Summarise(const std::vector<const StereoSample*>& s) {
  ErrorStats st;
  std::vector<double> e, rel;
  for (const StereoSample* p : s) {
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

namespace {

void PrintRow(const std::string& name, const ErrorStats& st) {
  const double gross = st.n + st.gross > 0 ? 100.0 * st.gross / (st.n + st.gross) : 0.0;
  std::printf("| %s | %d | %.1f | %+.4f | %.4f | %+.4f | %.4f | %+.3f | %+.3f |\n", name.c_str(),
              st.n, gross, st.mean, st.sd, st.median, st.mad, 100.0 * st.depth_mean,
              100.0 * st.depth_median);
}

}  // namespace

void PrintErrorTables(const std::vector<const StereoSample*>& samples, const std::string& title,
                      double bf, const std::vector<double>& depth_bounds) {
  const char* header =
      "| %s | n | gross (%%) | mean err (px) | SD (px) | median err (px) | 1.48 MAD (px) | depth "
      "err mean (%%) | depth err median (%%) |\n|---|---|---|---|---|---|---|---|---|\n";
  std::printf("\n%s, per octave (error = estimate - truth, level-0 px):\n\n", title.c_str());
  std::printf(header, "octave");
  std::vector<const StereoSample*> all;
  for (int o = 0; o < 8; ++o) {
    std::vector<const StereoSample*> s;
    for (const StereoSample* p : samples) {
      if (p->octave == o) s.push_back(p);
    }
    all.insert(all.end(), s.begin(), s.end());
    if (!s.empty()) PrintRow(std::to_string(o), Summarise(s));
  }
  PrintRow("all", Summarise(all));
  std::printf("\n%s, per true depth:\n\n", title.c_str());
  std::printf(header, "depth (disparity)");
  for (size_t b = 0; b < depth_bounds.size(); ++b) {
    const bool last = b + 1 == depth_bounds.size();
    const double lo = depth_bounds[b], hi = last ? 1e9 : depth_bounds[b + 1];
    std::vector<const StereoSample*> s;
    for (const StereoSample* p : samples) {
      const double z = bf / p->truth;
      if (z >= lo && z < hi) s.push_back(p);
    }
    if (s.empty()) continue;
    const std::string name =
        last     ? fmt::format("> {} m (< {:.1f} px)", lo, bf / lo)
        : b == 0 ? fmt::format("{}-{} m (> {:.1f} px)", lo, hi, bf / hi)
                 : fmt::format("{}-{} m ({:.1f}-{:.1f} px)", lo, hi, bf / hi, bf / lo);
    PrintRow(name, Summarise(s));
  }
}

}  // namespace moslam::tools
