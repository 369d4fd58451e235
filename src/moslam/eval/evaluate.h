// File-level entry points of the evaluator: what `moslam eval ate|rpe` runs, as a library
// function so that tests can exercise the command without starting the binary.
#pragma once

#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "moslam/eval/ate.h"
#include "moslam/eval/plot.h"
#include "moslam/eval/rpe.h"
#include "moslam/eval/trajectory.h"
#include "moslam/eval/trajectory_io.h"

namespace moslam::eval {

struct TrajectoryInputs {
  std::string gt_path;
  std::string est_path;
  TrajectoryFormat gt_format = TrajectoryFormat::kAuto;
  TrajectoryFormat est_format = TrajectoryFormat::kAuto;
  std::string gt_times;  // optional KITTI times.txt giving the ground truth its stamps
};

struct TrajectoryPair {
  Trajectory gt;
  Trajectory est;
};
// Reads both files (InputError naming file and line on bad input) and attaches gt_times.
TrajectoryPair LoadTrajectories(const TrajectoryInputs& inputs);

// "tum", "evo", or "auto": tum when both trajectories have timestamps (the TUM RGB-D tools are
// the reference there), evo when they are matched by index (KITTI files, evaluated with evo).
Convention ResolveConvention(const std::string& name, const Trajectory& gt, const Trajectory& est);

enum class Metric { kAte, kRpe };

// Everything `moslam eval ate|rpe` takes; unset optionals take the convention's defaults.
struct EvalRequest {
  Metric metric = Metric::kAte;
  TrajectoryInputs inputs;
  std::string convention = "auto";
  std::optional<std::string> alignment;   // default: se3 for ate, none for rpe
  std::optional<double> max_dt;           // default: 0.02 s (tum), 0.01 s (evo)
  double offset = 0.0;                    // seconds, added to the estimate's stamps
  double delta = 1.0;                     // rpe
  std::optional<std::string> delta_unit;  // rpe; default: s (tum), f (evo)
  bool all_pairs = false;                 // rpe
  size_t max_pairs = 10000;               // rpe, tum convention; 0 = all
  bool rotation = false;                  // report the rotation error (deg) instead of translation
  bool json = false;                      // JSON instead of the text table
  std::string plot_path;                  // optional .png / .svg (eval/plot.h)
};

// Options after defaults, for a request and its loaded trajectories.
AteOptions MakeAteOptions(const EvalRequest& request, const TrajectoryPair& trajectories);
RpeOptions MakeRpeOptions(const EvalRequest& request, const TrajectoryPair& trajectories);

struct EvalOutput {
  std::string text;                        // what the command prints on stdout
  std::optional<TrajectoryPlotData> plot;  // set when request.plot_path is
};
// Loads and evaluates. The caller prints `text` before writing the plot, so that a failing plot
// does not hide the numbers.
EvalOutput RunEvaluation(const EvalRequest& request);

}  // namespace moslam::eval
