#include "moslam/eval/plot_axes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

namespace moslam::eval::internal {
namespace {

constexpr double kTickLength = 5.0;
constexpr double kSwatch = 30.0;  // legend line sample length
constexpr double kLegendRow = 22.0;
constexpr double kLegendPad = 8.0;
constexpr Rgb kLegendFrame{200, 200, 200};

// The centre of the pixel column or row holding `v`, so 1-px lines stay crisp in the raster.
double Snap(double v) { return std::floor(v) + 0.5; }

PolylineShape Line(cv::Point2d a, cv::Point2d b, Rgb color, double width = 1.0) {
  return PolylineShape{{a, b}, color, width, false};
}

void DrawSwatch(Figure& figure, const LegendEntry& entry, double x, double y_mid) {
  switch (entry.kind) {
    case LegendEntry::Kind::kLine:
    case LegendEntry::Kind::kDashed:
      figure.Add(PolylineShape{{{x, y_mid}, {x + kSwatch, y_mid}},
                               entry.color,
                               entry.width,
                               entry.kind == LegendEntry::Kind::kDashed});
      break;
    case LegendEntry::Kind::kGradient: {
      constexpr int kSteps = 6;
      for (int i = 0; i < kSteps; ++i) {
        const double a = x + kSwatch * i / kSteps;
        const double b = x + kSwatch * (i + 1) / kSteps;
        figure.Add(Line({a, y_mid}, {b, y_mid}, Plasma((i + 0.5) / kSteps), entry.width));
      }
      break;
    }
    case LegendEntry::Kind::kRing:
      figure.Add(CircleShape{{x + kSwatch / 2, y_mid}, 6.0, entry.color});
      figure.Add(CircleShape{{x + kSwatch / 2, y_mid}, 3.5, Rgb{255, 255, 255}});
      break;
  }
}

double LegendLabelWidth(const std::vector<LegendEntry>& entries) {
  double width = 0.0;
  for (const auto& entry : entries) width = std::max(width, TextWidth(entry.label, kLegendSize));
  return width;
}

}  // namespace

void AddText(Figure& figure, std::string text, cv::Point2d baseline, double size, Anchor anchor,
             Rgb color, bool bold, bool vertical) {
  figure.Add(TextShape{std::move(text), baseline, size, color, anchor, bold, vertical});
}

cv::Point2d Axes::ToPixel(double u, double v) const {
  return {box.x + (u - x.lo) / x.Span() * box.width,
          box.y + box.height - (v - y.lo) / y.Span() * box.height};
}

// Small panels ask for few ticks; if the rounded step leaves fewer than three inside the range,
// ask for more.
Ticks AtLeastThreeTicks(Range range, int target) {
  Ticks ticks = NiceTicks(range, target);
  for (int more = target + 1; ticks.values.size() < 3 && more <= 3 * target; ++more) {
    ticks = NiceTicks(range, more);
  }
  return ticks;
}

Ticks Axes::XTicks() const {
  return AtLeastThreeTicks(x, std::clamp(static_cast<int>(box.width / 100.0), 2, 10));
}

Ticks Axes::YTicks() const {
  return AtLeastThreeTicks(y, std::clamp(static_cast<int>(box.height / 50.0), 3, 10));
}

void DrawGrid(Figure& figure, const Axes& axes) {
  const double top = axes.box.y, bottom = axes.box.y + axes.box.height;
  const double left = axes.box.x, right = axes.box.x + axes.box.width;
  for (const double t : axes.XTicks().values) {
    const double px = Snap(axes.ToPixel(t, axes.y.lo).x);
    figure.Add(Line({px, top}, {px, bottom}, kGrid));
  }
  for (const double t : axes.YTicks().values) {
    const double py = Snap(axes.ToPixel(axes.x.lo, t).y);
    figure.Add(Line({left, py}, {right, py}, kGrid));
  }
}

void DrawFrame(Figure& figure, const Axes& axes, const AxisText& text) {
  const cv::Rect2d& box = axes.box;
  const double bottom = box.y + box.height;
  figure.Add(RectShape{box, kFrame, false, 1.0});
  const double cap = kCapHeight * kTickSize;

  const Ticks x_ticks = axes.XTicks();
  for (const double t : x_ticks.values) {
    const double px = Snap(axes.ToPixel(t, axes.y.lo).x);
    figure.Add(Line({px, bottom}, {px, bottom + kTickLength}, kFrame));
    if (text.x_tick_labels) {
      AddText(figure, FormatTick(t, x_ticks.step), {px, bottom + kTickLength + 4 + cap}, kTickSize,
              Anchor::kMiddle);
    }
  }
  const Ticks y_ticks = axes.YTicks();
  double widest = 0.0;
  for (const double t : y_ticks.values) {
    const double py = Snap(axes.ToPixel(axes.x.lo, t).y);
    figure.Add(Line({box.x - kTickLength, py}, {box.x, py}, kFrame));
    if (text.y_tick_labels) {
      const std::string label = FormatTick(t, y_ticks.step);
      widest = std::max(widest, TextWidth(label, kTickSize));
      AddText(figure, label, {box.x - kTickLength - 4, py + cap / 2}, kTickSize, Anchor::kEnd);
    }
  }
  if (!text.x_label.empty()) {
    AddText(figure, text.x_label, {box.x + box.width / 2, bottom + kTickLength + 2 * cap + 24},
            kLabelSize, Anchor::kMiddle);
  }
  if (!text.y_label.empty()) {
    // Vertical text extends left of its baseline by the cap height, right by descenders.
    const double x = box.x - kTickLength - 4 - widest - 10 - 0.25 * kLabelSize;
    AddText(figure, text.y_label, {x, box.y + box.height / 2}, kLabelSize, Anchor::kMiddle, kInk,
            false, true);
  }
}

std::vector<cv::Point2d> DrawSeries(Figure& figure, const Axes& axes, const std::vector<double>& u,
                                    const std::vector<double>& v, Rgb color, double width,
                                    bool dashed) {
  const size_t n = std::min(u.size(), v.size());
  std::vector<cv::Point2d> pixels(n);
  for (size_t i = 0; i < n; ++i) pixels[i] = axes.ToPixel(u[i], v[i]);
  for (const auto& run : DecimatedRuns(pixels, 1.0)) {
    PolylineShape line{{}, color, width, dashed};
    line.points.reserve(run.size());
    for (const size_t i : run) line.points.push_back(pixels[i]);
    figure.Add(std::move(line));
  }
  return pixels;
}

void DrawLegendBox(Figure& figure, const Axes& axes, const std::vector<LegendEntry>& entries,
                   const std::vector<cv::Point2d>& points) {
  const double width = 3 * kLegendPad + kSwatch + LegendLabelWidth(entries);
  const double height = kLegendPad + kLegendRow * static_cast<double>(entries.size());
  const cv::Rect2d& box = axes.box;
  const double inset = 10.0;
  const double left = box.x + inset, right = box.x + box.width - inset - width;
  const double top = box.y + inset, bottom = box.y + box.height - inset - height;
  // Matplotlib's loc="best" order of preference: upper right, upper left, lower left, lower right.
  const std::array<cv::Point2d, 4> corners = {
      {{right, top}, {left, top}, {left, bottom}, {right, bottom}}};
  cv::Point2d best = corners[0];
  size_t fewest = std::numeric_limits<size_t>::max();
  for (const cv::Point2d& corner : corners) {
    const cv::Rect2d area(corner.x, corner.y, width, height);
    const auto covered = static_cast<size_t>(std::count_if(
        points.begin(), points.end(), [&](const cv::Point2d& p) { return area.contains(p); }));
    if (covered < fewest) {
      fewest = covered;
      best = corner;
    }
  }
  const cv::Rect2d frame(std::round(best.x), std::round(best.y), std::round(width),
                         std::round(height));
  figure.Add(RectShape{frame, Rgb{255, 255, 255}, true, 1.0});
  figure.Add(RectShape{frame, kLegendFrame, false, 1.0});
  for (size_t i = 0; i < entries.size(); ++i) {
    const double y_mid = frame.y + kLegendPad / 2 + kLegendRow * (static_cast<double>(i) + 0.5);
    DrawSwatch(figure, entries[i], frame.x + kLegendPad, y_mid);
    AddText(figure, entries[i].label,
            {frame.x + 2 * kLegendPad + kSwatch, y_mid + kCapHeight * kLegendSize / 2}, kLegendSize,
            Anchor::kStart);
  }
}

void DrawLegendRow(Figure& figure, double right, double baseline,
                   const std::vector<LegendEntry>& entries) {
  constexpr double kGap = 22.0;
  double total = 0.0;
  for (const auto& entry : entries) {
    total += kSwatch + kLegendPad + TextWidth(entry.label, kLegendSize) + kGap;
  }
  double x = right - (total - kGap);
  const double y_mid = baseline - kCapHeight * kLegendSize / 2;
  for (const auto& entry : entries) {
    DrawSwatch(figure, entry, x, y_mid);
    x += kSwatch + kLegendPad;
    AddText(figure, entry.label, {x, baseline}, kLegendSize, Anchor::kStart);
    x += TextWidth(entry.label, kLegendSize) + kGap;
  }
}

}  // namespace moslam::eval::internal
