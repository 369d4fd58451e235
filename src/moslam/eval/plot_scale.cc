#include "moslam/eval/plot_scale.h"

#include <algorithm>
#include <array>
#include <cmath>

#include <fmt/format.h>

namespace moslam::eval::internal {
namespace {

// Heckbert's nicenum() with rounding: the 1, 2, 5 or 10 x 10^k nearest to x.
double NiceNumber(double x) {
  const double exponent = std::floor(std::log10(x));
  const double fraction = x / std::pow(10.0, exponent);
  const double nice = fraction < 1.5 ? 1.0 : fraction < 3.0 ? 2.0 : fraction < 7.0 ? 5.0 : 10.0;
  return nice * std::pow(10.0, exponent);
}

int DecimalsFor(double step) {
  if (!(step > 0.0) || !std::isfinite(step)) return 0;
  // The small epsilon keeps steps like 0.1 (stored as 0.1000000000000000055) at one decimal.
  return std::clamp(static_cast<int>(-std::floor(std::log10(step) + 1e-9)), 0, 12);
}

}  // namespace

Range FiniteRange(const std::vector<double>& values, Range fallback) {
  Range range{INFINITY, -INFINITY};
  for (const double v : values) {
    if (!std::isfinite(v)) continue;
    range.lo = std::min(range.lo, v);
    range.hi = std::max(range.hi, v);
  }
  return range.lo <= range.hi ? range : fallback;
}

Range Padded(Range range, double fraction) {
  const double magnitude = std::max({1.0, std::abs(range.lo), std::abs(range.hi)});
  if (range.Span() <= 1e-12 * magnitude) {
    const double center = 0.5 * (range.lo + range.hi);
    const double half = std::max(0.5, 0.05 * std::abs(center));
    return {center - half, center + half};
  }
  const double pad = fraction * range.Span();
  return {range.lo - pad, range.hi + pad};
}

Ticks NiceTicks(Range range, int target) {
  Ticks ticks;
  const double span = range.Span();
  if (!(span > 0.0) || !std::isfinite(span) || target < 2) return ticks;
  ticks.step = NiceNumber(span / (target - 1));
  // Tolerate rounding so that a tick exactly at an end of the range is kept.
  const double eps = 1e-9 * ticks.step;
  const double first = std::ceil((range.lo - eps) / ticks.step);
  const double last = std::floor((range.hi + eps) / ticks.step);
  for (double k = first; k <= last && ticks.values.size() < 100; k += 1.0) {
    ticks.values.push_back(k * ticks.step);
  }
  return ticks;
}

std::string FormatTick(double value, double step) {
  if (std::abs(value) < 1e-9 * step) value = 0.0;  // no "-0.0"
  return fmt::format("{:.{}f}", value, DecimalsFor(step));
}

std::string FormatValue(double value) {
  if (!std::isfinite(value)) return "n/a";
  if (value == 0.0) return "0";
  const double magnitude = std::abs(value);
  if (magnitude >= 1e5 || magnitude < 1e-4) return fmt::format("{:.2e}", value);
  // Three significant digits in fixed notation, e.g. 0.000337, 0.00814, 1.23, 123.
  const int decimals = std::max(0, 2 - static_cast<int>(std::floor(std::log10(magnitude))));
  return fmt::format("{:.{}f}", value, decimals);
}

Rgb Plasma(double t) {
  // Samples of matplotlib's plasma at 0, 0.2, 0.4, 0.6 and 0.8, interpolated linearly.
  static constexpr std::array<std::array<double, 3>, 5> kStops = {
      {{13, 8, 135}, {106, 0, 168}, {177, 42, 144}, {225, 100, 98}, {252, 166, 54}}};
  if (!std::isfinite(t)) t = 0.0;
  const double x = std::clamp(t, 0.0, 1.0) * (kStops.size() - 1);
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(x), kStops.size() - 2);
  const double f = x - static_cast<double>(i);
  auto mix = [&](int c) {
    return static_cast<std::uint8_t>(std::lround((1.0 - f) * kStops[i][c] + f * kStops[i + 1][c]));
  };
  return {mix(0), mix(1), mix(2)};
}

std::vector<std::vector<std::size_t>> DecimatedRuns(const std::vector<cv::Point2d>& pixels,
                                                    double min_step) {
  std::vector<std::vector<std::size_t>> runs;
  const double min_step2 = min_step * min_step;
  bool in_run = false;
  std::size_t last_in_run = 0;
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const cv::Point2d& p = pixels[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y)) {
      if (in_run && runs.back().back() != last_in_run) runs.back().push_back(last_in_run);
      in_run = false;
      continue;
    }
    if (!in_run) {
      runs.push_back({i});
      in_run = true;
    } else {
      const cv::Point2d d = p - pixels[runs.back().back()];
      if (d.dot(d) >= min_step2) runs.back().push_back(i);
    }
    last_in_run = i;
  }
  if (in_run && runs.back().back() != last_in_run) runs.back().push_back(last_in_run);
  return runs;
}

}  // namespace moslam::eval::internal
