// Axes, series and legends of the trajectory plot, drawn into a Figure (plot_figure.h).
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/eval/plot_figure.h"
#include "moslam/eval/plot_scale.h"

namespace moslam::eval::internal {

// Palette: matplotlib's "tab10" blue and red for data, greys for ink, grid and reference.
inline constexpr Rgb kInk{34, 34, 34};
inline constexpr Rgb kFrame{110, 110, 110};
inline constexpr Rgb kGrid{228, 228, 228};
inline constexpr Rgb kReference{140, 140, 140};
inline constexpr Rgb kEstimate{31, 119, 180};
inline constexpr Rgb kError{214, 39, 40};
inline constexpr Rgb kMissing{190, 190, 190};

// Font sizes in pixels.
inline constexpr double kTitleSize = 26.0;
inline constexpr double kHeadingSize = 19.0;
inline constexpr double kLabelSize = 17.0;
inline constexpr double kTickSize = 14.0;
inline constexpr double kLegendSize = 15.0;

void AddText(Figure& figure, std::string text, cv::Point2d baseline, double size, Anchor anchor,
             Rgb color = kInk, bool bold = false, bool vertical = false);

// A data rectangle: pixel box and the data ranges it shows (y up).
struct Axes {
  cv::Rect2d box;
  Range x, y;

  // NaN in, NaN out, so that missing values break lines (DecimatedRuns).
  cv::Point2d ToPixel(double u, double v) const;
  Ticks XTicks() const;
  Ticks YTicks() const;
};

// Light grid lines at the ticks; drawn before the data.
void DrawGrid(Figure& figure, const Axes& axes);

struct AxisText {
  bool x_tick_labels = true;
  bool y_tick_labels = true;
  std::string x_label;  // below the tick labels; empty: none
  std::string y_label;  // vertical, left of the tick labels; empty: none
};
// Frame, tick marks, tick labels and axis labels; drawn after the data.
void DrawFrame(Figure& figure, const Axes& axes, const AxisText& text);

// The curve (u[i], v[i]) as decimated polylines; isolated points become dots. Returns the pixel
// position of every point (NaN where skipped), e.g. for legend placement.
std::vector<cv::Point2d> DrawSeries(Figure& figure, const Axes& axes, const std::vector<double>& u,
                                    const std::vector<double>& v, Rgb color, double width,
                                    bool dashed = false);

struct LegendEntry {
  enum class Kind { kLine, kDashed, kGradient, kRing };
  std::string label;
  Kind kind = Kind::kLine;
  Rgb color;
  double width = 2.0;
};
// A boxed legend in the corner of `axes` that covers the fewest of `points` (pixels).
void DrawLegendBox(Figure& figure, const Axes& axes, const std::vector<LegendEntry>& entries,
                   const std::vector<cv::Point2d>& points);
// A one-line legend without a box, ending at x = `right`, on `baseline`.
void DrawLegendRow(Figure& figure, double right, double baseline,
                   const std::vector<LegendEntry>& entries);

}  // namespace moslam::eval::internal
