// Layout of the trajectory figure: turns TrajectoryPlotData into a backend-neutral Figure.
#pragma once

#include "moslam/eval/plot.h"
#include "moslam/eval/plot_figure.h"

namespace moslam::eval::internal {

// The 1600 x 1000 px figure: title; top view with colour bar (left); x, y, z over time and the
// error over time with its RMSE (right). `data` must have consistent, non-zero lengths (checked by
// WriteTrajectoryPlot); non-finite values are skipped.
Figure LayoutTrajectoryPlot(const TrajectoryPlotData& data);

}  // namespace moslam::eval::internal
