// Numeric helpers of the trajectory plot: axis ranges, "nice" tick values, tick labels, the error
// colour map and decimation of polylines in pixel space.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "moslam/eval/plot_figure.h"

namespace moslam::eval::internal {

struct Range {
  double lo = 0.0;
  double hi = 1.0;
  double Span() const { return hi - lo; }
};

// Min and max of the finite values in `values`, or `fallback` when there are none.
Range FiniteRange(const std::vector<double>& values, Range fallback = {-1.0, 1.0});
// Widens `range` by `fraction` of its span on each side. A (numerically) zero span, e.g. a
// constant coordinate or a single pose, gets half-width max(0.5, 5% of |value|) instead so the
// axis stays readable.
Range Padded(Range range, double fraction);

struct Ticks {
  std::vector<double> values;  // inside the range, ascending
  double step = 0.0;
};
// About `target` tick values in `range` at multiples of 1, 2 or 5 x 10^k, after P. S. Heckbert,
// "Nice numbers for graph labels", Graphics Gems, 1990: the step is nicenum(span / (target - 1))
// rounded to the nearest 1, 2, 5 x 10^k (without Heckbert's first rounding of the span, which can
// double the step, e.g. span 101 -> 200 -> step 50 instead of 20). Only ticks inside the range
// are kept: the axes span the data, not the rounded-out tick range.
Ticks NiceTicks(Range range, int target);
// `value` with just enough decimals to tell ticks `step` apart; never "-0".
std::string FormatTick(double value, double step);
// `value` with 3 significant digits, for colour bar ends and summary values.
std::string FormatValue(double value);

// Matplotlib's "plasma" colour map (perceptually uniform, readable in grey scale), truncated at
// 0.8 so that the bright end stays visible on white; t in [0, 1] is clamped.
Rgb Plasma(double t);

// Splits `pixels` into runs of consecutive finite points (a non-finite point breaks the line) and
// decimates each run: a point closer than `min_step` pixels to the last kept one is dropped,
// except the last point of a run. Returns the indices of the kept points, one vector per run.
// This keeps 20,000-pose trajectories to a few thousand drawn segments without visible change.
std::vector<std::vector<std::size_t>> DecimatedRuns(const std::vector<cv::Point2d>& pixels,
                                                    double min_step);

}  // namespace moslam::eval::internal
