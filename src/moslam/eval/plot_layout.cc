#include "moslam/eval/plot_layout.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "moslam/eval/plot_axes.h"
#include "moslam/eval/plot_scale.h"

namespace moslam::eval::internal {
namespace {

// Layout of the 1600 x 1000 px figure, in pixels. Left: top view and its colour bar; right: three
// position panels sharing the time axis, and the error panel below them.
constexpr int kWidth = 1600;
constexpr int kHeight = 1000;
constexpr double kTitleBaseline = 46.0;
constexpr double kHeadingBaseline = 86.0;
const cv::Rect2d kTopViewBox(100, 105, 600, 800);
const cv::Rect2d kColourBar(722, 185, 16, 480);
constexpr double kRightX = 960.0;
constexpr double kRightWidth = 610.0;
constexpr double kPositionTop = 105.0;
constexpr double kPositionHeight = 150.0;
constexpr double kPositionGap = 16.0;
constexpr double kErrorHeadingBaseline = 688.0;
const cv::Rect2d kErrorBox(kRightX, 705, kRightWidth, 200);
constexpr int kColourLevels = 64;  // error colours are quantized so that segments merge
constexpr const char* kAxisNames[3] = {"x", "y", "z"};

// The input split into plain per-coordinate series, with times relative to the first pose. A
// time gap (lost tracking: no compared poses) becomes a row of NaN so that lines break there.
struct Series {
  size_t poses = 0;
  std::vector<double> time;
  std::array<std::vector<double>, 3> reference, estimate;
  std::vector<double> errors;
  Range time_range;
  Range error_values;  // finite min and max; lo > hi when there is none
  double rmse = NAN;
  bool colour_by_error = false;
};

// A step in time is a gap when it is longer than both kGapSteps median steps and kGapFraction of
// the whole duration: long tracking losses break the lines, a few dropped frames do not.
constexpr double kGapSteps = 20.0;
constexpr double kGapFraction = 0.02;

// Median of the positive finite steps between consecutive times; 0 when there is none.
double MedianStep(const std::vector<double>& times) {
  std::vector<double> steps;
  for (size_t i = 1; i < times.size(); ++i) {
    const double dt = times[i] - times[i - 1];
    if (std::isfinite(dt) && dt > 0.0) steps.push_back(dt);
  }
  if (steps.empty()) return 0.0;
  std::nth_element(steps.begin(), steps.begin() + steps.size() / 2, steps.end());
  return steps[steps.size() / 2];
}

void AppendRow(Series& s, double time, const Eigen::Vector3d& reference,
               const Eigen::Vector3d& estimate) {
  s.time.push_back(time);
  for (int k = 0; k < 3; ++k) {
    s.reference[k].push_back(reference[k]);
    s.estimate[k].push_back(estimate[k]);
  }
}

Series Prepare(const TrajectoryPlotData& data) {
  Series s;
  const size_t n = data.times.size();
  s.poses = n;
  const auto first =
      std::find_if(data.times.begin(), data.times.end(), [](double t) { return std::isfinite(t); });
  const double t0 = first == data.times.end() ? 0.0 : *first;
  const Range span = FiniteRange(data.times, {0.0, 0.0});
  const double max_step = std::max(kGapSteps * MedianStep(data.times), kGapFraction * span.Span());
  const Eigen::Vector3d gap = Eigen::Vector3d::Constant(NAN);
  for (size_t i = 0; i < n; ++i) {
    if (i > 0 && max_step > 0.0 && data.times[i] - data.times[i - 1] > max_step) {
      AppendRow(s, NAN, gap, gap);
      if (i < data.errors.size()) s.errors.push_back(NAN);
    }
    AppendRow(s, data.times[i] - t0, data.reference[i], data.estimate[i]);
    if (i < data.errors.size()) s.errors.push_back(data.errors[i]);
  }
  s.time_range = Padded(FiniteRange(s.time, {0.0, 1.0}), 0.01);
  s.error_values = FiniteRange(s.errors, {INFINITY, -INFINITY});
  double sum_squares = 0.0;
  size_t count = 0;
  for (const double e : s.errors) {
    if (!std::isfinite(e)) continue;
    sum_squares += e * e;
    ++count;
  }
  if (count > 0) s.rmse = std::sqrt(sum_squares / static_cast<double>(count));
  s.colour_by_error = count > 0 && data.errors.size() == n;
  return s;
}

std::vector<double> Concat(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<double> all = a;
  all.insert(all.end(), b.begin(), b.end());
  return all;
}

// The two coordinates with the largest extent, in x, y, z order (x-z for camera-style KITTI
// trajectories where y points down, x-y for TUM ground truth).
std::array<int, 2> TopViewCoordinates(const Series& s) {
  std::array<double, 3> extent{};
  for (int k = 0; k < 3; ++k) {
    const Range r = FiniteRange(Concat(s.reference[k], s.estimate[k]), {0.0, 0.0});
    extent[k] = r.Span();
  }
  std::array<int, 3> order = {0, 1, 2};
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return extent[a] > extent[b]; });
  return {std::min(order[0], order[1]), std::max(order[0], order[1])};
}

// Widens the smaller of the two ranges so that one metre is as long on both axes.
Axes EqualAspect(const cv::Rect2d& box, Range u, Range v) {
  const double px_per_unit = std::min(box.width / u.Span(), box.height / v.Span());
  auto centred = [&](Range r, double pixels) {
    const double mid = 0.5 * (r.lo + r.hi), half = 0.5 * pixels / px_per_unit;
    return Range{mid - half, mid + half};
  };
  return Axes{box, centred(u, box.width), centred(v, box.height)};
}

double ColourPosition(double error, Range values) {
  return values.Span() > 0.0 ? (error - values.lo) / values.Span() : 0.5;
}

// The estimate as polylines coloured by error. Each segment takes the mean error of the poses it
// stands for after decimation (at most a pixel of path, so nothing visible is averaged away).
std::vector<cv::Point2d> DrawColouredPath(Figure& figure, const Axes& axes,
                                          const std::vector<double>& u,
                                          const std::vector<double>& v, const Series& s) {
  std::vector<cv::Point2d> pixels(u.size());
  for (size_t i = 0; i < u.size(); ++i) pixels[i] = axes.ToPixel(u[i], v[i]);
  auto level_of = [&](double e) {
    if (!std::isfinite(e)) return -1;
    return static_cast<int>(std::lround(ColourPosition(e, s.error_values) * (kColourLevels - 1)));
  };
  auto colour_of = [](int level) {
    return level < 0 ? kMissing : Plasma(static_cast<double>(level) / (kColourLevels - 1));
  };
  for (const auto& run : DecimatedRuns(pixels, 1.0)) {
    if (run.size() == 1) {
      figure.Add(PolylineShape{{pixels[run[0]]}, colour_of(level_of(s.errors[run[0]])), 3.0});
      continue;
    }
    PolylineShape line;
    int line_level = -2;
    for (size_t j = 1; j < run.size(); ++j) {
      double sum = 0.0;
      int count = 0;
      for (size_t i = run[j - 1] + 1; i <= run[j]; ++i) {
        if (!std::isfinite(s.errors[i])) continue;
        sum += s.errors[i];
        ++count;
      }
      const int level = level_of(count > 0 ? sum / count : NAN);
      if (level != line_level) {
        if (line.points.size() >= 2) figure.Add(std::move(line));
        line = PolylineShape{{pixels[run[j - 1]]}, colour_of(level), 2.0};
        line_level = level;
      }
      line.points.push_back(pixels[run[j]]);
    }
    if (line.points.size() >= 2) figure.Add(std::move(line));
  }
  return pixels;
}

void DrawColourBar(Figure& figure, const Series& s, const std::string& label) {
  const cv::Rect2d& bar = kColourBar;
  constexpr int kSteps = 100;
  for (int i = 0; i < kSteps; ++i) {
    // Bottom = smallest error. Each band reaches a pixel into the one below (drawn earlier) to
    // avoid seams, except the lowest.
    const double y0 = bar.y + bar.height * (kSteps - 1 - i) / kSteps;
    const double height = bar.height / kSteps + (i > 0 ? 1.0 : 0.0);
    figure.Add(RectShape{cv::Rect2d(bar.x, y0, bar.width, height), Plasma((i + 0.5) / kSteps)});
  }
  figure.Add(RectShape{bar, kFrame, false, 1.0});
  const Range values = s.error_values;
  const double cap = kCapHeight * kTickSize;
  const double label_x = bar.x + bar.width + 8;
  auto y_of = [&](double e) { return bar.y + bar.height * (1.0 - ColourPosition(e, values)); };
  double widest = 0.0;
  auto tick = [&](double e, const std::string& text) {
    const double y = std::floor(y_of(e)) + 0.5;
    figure.Add(PolylineShape{{{bar.x + bar.width, y}, {bar.x + bar.width + 4, y}}, kFrame, 1.0});
    AddText(figure, text, {label_x, y + cap / 2}, kTickSize, Anchor::kStart);
    widest = std::max(widest, TextWidth(text, kTickSize));
  };
  tick(values.hi, FormatValue(values.hi));
  if (values.Span() > 0.0) {
    tick(values.lo, FormatValue(values.lo));
    const Ticks ticks = NiceTicks(values, 6);
    for (const double t : ticks.values) {
      // Keep inner ticks clear of the min/max labels.
      if (std::abs(y_of(t) - y_of(values.lo)) < 22 || std::abs(y_of(t) - y_of(values.hi)) < 22) {
        continue;
      }
      tick(t, FormatTick(t, ticks.step));
    }
  }
  AddText(figure, label, {label_x + widest + 12 + kCapHeight * kLabelSize, bar.y + bar.height / 2},
          kLabelSize, Anchor::kMiddle, kInk, false, true);
}

void DrawTopView(Figure& figure, const Series& s, const std::string& error_label) {
  const auto [a, b] = TopViewCoordinates(s);
  const Range u = Padded(FiniteRange(Concat(s.reference[a], s.estimate[a])), 0.04);
  const Range v = Padded(FiniteRange(Concat(s.reference[b], s.estimate[b])), 0.04);
  const Axes axes = EqualAspect(kTopViewBox, u, v);
  AddText(figure,
          fmt::format("Top view ({}-{}), {} pose{}", kAxisNames[a], kAxisNames[b], s.poses,
                      s.poses == 1 ? "" : "s"),
          {kTopViewBox.x, kHeadingBaseline}, kHeadingSize, Anchor::kStart, kInk, true);
  DrawGrid(figure, axes);
  std::vector<cv::Point2d> drawn =
      DrawSeries(figure, axes, s.reference[a], s.reference[b], kReference, 3.0);
  std::vector<LegendEntry> legend = {{"ground truth", LegendEntry::Kind::kLine, kReference, 3.0}};
  std::vector<cv::Point2d> estimate;
  if (s.colour_by_error) {
    estimate = DrawColouredPath(figure, axes, s.estimate[a], s.estimate[b], s);
    legend.push_back({"estimate, colour = error", LegendEntry::Kind::kGradient, kEstimate, 3.0});
  } else {
    estimate = DrawSeries(figure, axes, s.estimate[a], s.estimate[b], kEstimate, 2.0);
    legend.push_back({"estimate", LegendEntry::Kind::kLine, kEstimate, 2.0});
  }
  drawn.insert(drawn.end(), estimate.begin(), estimate.end());
  // Mark where the trajectory starts, as a ring that the lines show through.
  for (size_t i = 0; i < s.time.size(); ++i) {
    const cv::Point2d p = axes.ToPixel(s.reference[a][i], s.reference[b][i]);
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) continue;
    figure.Add(CircleShape{p, 6.0, kInk});
    figure.Add(CircleShape{p, 3.5, Rgb{255, 255, 255}});
    legend.push_back({"start", LegendEntry::Kind::kRing, kInk, 1.0});
    break;
  }
  DrawFrame(
      figure, axes,
      {true, true, fmt::format("{} [m]", kAxisNames[a]), fmt::format("{} [m]", kAxisNames[b])});
  DrawLegendBox(figure, axes, legend, drawn);
  if (s.colour_by_error) DrawColourBar(figure, s, error_label);
}

void DrawPositions(Figure& figure, const Series& s, const std::string& time_label) {
  AddText(figure, "Position over time", {kRightX, kHeadingBaseline}, kHeadingSize, Anchor::kStart,
          kInk, true);
  DrawLegendRow(figure, kRightX + kRightWidth, kHeadingBaseline,
                {{"ground truth", LegendEntry::Kind::kLine, kReference, 3.0},
                 {"estimate", LegendEntry::Kind::kLine, kEstimate, 2.0}});
  for (int k = 0; k < 3; ++k) {
    const cv::Rect2d box(kRightX, kPositionTop + k * (kPositionHeight + kPositionGap), kRightWidth,
                         kPositionHeight);
    const Axes axes{box, s.time_range,
                    Padded(FiniteRange(Concat(s.reference[k], s.estimate[k])), 0.08)};
    DrawGrid(figure, axes);
    DrawSeries(figure, axes, s.time, s.reference[k], kReference, 3.0);
    DrawSeries(figure, axes, s.time, s.estimate[k], kEstimate, 2.0);
    const bool last = k == 2;
    DrawFrame(
        figure, axes,
        {last, true, last ? time_label : std::string(), fmt::format("{} [m]", kAxisNames[k])});
  }
}

void DrawErrors(Figure& figure, const Series& s, const std::string& error_label,
                const std::string& time_label) {
  AddText(figure, "Error over time", {kRightX, kErrorHeadingBaseline}, kHeadingSize, Anchor::kStart,
          kInk, true);
  const bool any = s.error_values.lo <= s.error_values.hi;
  Range range{std::min(0.0, any ? s.error_values.lo : 0.0), any ? s.error_values.hi : 1.0};
  // Errors are magnitudes: the axis starts at zero; all-zero errors get a unit axis.
  range = range.Span() > 0.0 ? Range{range.lo, range.hi + 0.08 * range.Span()}
                             : Range{range.lo, range.lo + 1.0};
  const Axes axes{kErrorBox, s.time_range, range};
  DrawGrid(figure, axes);
  if (!any) {
    AddText(figure, "no error values",
            {kErrorBox.x + kErrorBox.width / 2, kErrorBox.y + kErrorBox.height / 2}, kLabelSize,
            Anchor::kMiddle, kFrame);
  } else {
    const std::vector<double> time(s.time.begin(), s.time.begin() + s.errors.size());
    const std::vector<cv::Point2d> drawn = DrawSeries(figure, axes, time, s.errors, kError, 2.0);
    const double y = axes.ToPixel(0.0, s.rmse).y;
    figure.Add(
        PolylineShape{{{kErrorBox.x, y}, {kErrorBox.x + kErrorBox.width, y}}, kInk, 2.0, true});
    DrawLegendBox(
        figure, axes,
        {{fmt::format("error (max {})", FormatValue(s.error_values.hi)), LegendEntry::Kind::kLine,
          kError, 2.0},
         {fmt::format("RMSE = {}", FormatValue(s.rmse)), LegendEntry::Kind::kDashed, kInk, 2.0}},
        drawn);
  }
  DrawFrame(figure, axes, {true, true, time_label, error_label.empty() ? "error" : error_label});
}

}  // namespace

Figure LayoutTrajectoryPlot(const TrajectoryPlotData& data) {
  Figure figure;
  figure.width = kWidth;
  figure.height = kHeight;
  const Series s = Prepare(data);
  const std::string error_label = data.error_label.empty() ? "error" : data.error_label;
  AddText(figure, data.title.empty() ? "Trajectory" : data.title, {kWidth / 2.0, kTitleBaseline},
          kTitleSize, Anchor::kMiddle, kInk, true);
  DrawTopView(figure, s, error_label);
  const std::string time_label = data.time_label.empty() ? "time" : data.time_label;
  DrawPositions(figure, s, time_label);
  DrawErrors(figure, s, error_label, time_label);
  return figure;
}

}  // namespace moslam::eval::internal
