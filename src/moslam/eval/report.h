// Presenting results: aligned text tables (what the CLI prints), JSON, and plot data.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "moslam/eval/ate.h"
#include "moslam/eval/plot.h"
#include "moslam/eval/rpe.h"
#include "moslam/eval/statistics.h"
#include "moslam/eval/trajectory.h"

namespace moslam::eval {

// "compared_pose_pairs N", then rmse, mean, median, std, min, max, six decimals as the TUM tools
// print them, with names padded into a column.
std::string FormatStatistics(const ErrorStatistics& stats, const std::string& unit);

// Settings line, input summary and the statistics of the translation (or, with `rotation`, the
// rotation) error.
std::string FormatAteReport(const AteResult& result, const Trajectory& gt, const Trajectory& est,
                            bool rotation);
std::string FormatRpeReport(const RpeResult& result, const Trajectory& gt, const Trajectory& est,
                            bool rotation);

nlohmann::json StatisticsToJson(const ErrorStatistics& stats);
// Settings, inputs, the alignment transform and the statistics of both error kinds.
nlohmann::json AteToJson(const AteResult& result, const Trajectory& gt, const Trajectory& est);
nlohmann::json RpeToJson(const RpeResult& result, const Trajectory& gt, const Trajectory& est);

// Plot data: times are relative to the first compared pose; errors per pose (ATE) or per pair
// (RPE), translation in metres or rotation in degrees.
TrajectoryPlotData MakeAtePlotData(const AteResult& result, const Trajectory& est, bool rotation);
TrajectoryPlotData MakeRpePlotData(const RpeResult& result, const Trajectory& est, bool rotation);

}  // namespace moslam::eval
