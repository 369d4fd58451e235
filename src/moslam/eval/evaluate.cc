#include "moslam/eval/evaluate.h"

#include <spdlog/spdlog.h>

#include "moslam/eval/report.h"
#include "moslam/util/error.h"

namespace moslam::eval {

TrajectoryPair LoadTrajectories(const TrajectoryInputs& inputs) {
  TrajectoryPair pair;
  pair.gt = ReadTrajectory(inputs.gt_path, inputs.gt_format);
  pair.est = ReadTrajectory(inputs.est_path, inputs.est_format);
  if (!inputs.gt_times.empty()) AttachTimes(inputs.gt_times, &pair.gt);
  spdlog::debug("read {} poses from {} and {} from {}", pair.gt.size(), pair.gt.name,
                pair.est.size(), pair.est.name);
  return pair;
}

Convention ResolveConvention(const std::string& name, const Trajectory& gt, const Trajectory& est) {
  if (name != "auto") return ParseConvention(name);
  return gt.has_timestamps() && est.has_timestamps() ? Convention::kTum : Convention::kEvo;
}

AteOptions MakeAteOptions(const EvalRequest& request, const TrajectoryPair& trajectories) {
  AteOptions options = AteOptions::Defaults(
      ResolveConvention(request.convention, trajectories.gt, trajectories.est));
  if (request.alignment) options.alignment = ParseAlignmentMode(*request.alignment);
  if (request.max_dt) options.max_dt = *request.max_dt;
  options.offset = request.offset;
  options.Check();
  return options;
}

RpeOptions MakeRpeOptions(const EvalRequest& request, const TrajectoryPair& trajectories) {
  RpeOptions options = RpeOptions::Defaults(
      ResolveConvention(request.convention, trajectories.gt, trajectories.est));
  if (request.alignment) options.alignment = ParseAlignmentMode(*request.alignment);
  if (request.max_dt) options.max_dt = *request.max_dt;
  if (request.delta_unit) options.delta_unit = ParseDeltaUnit(*request.delta_unit);
  options.offset = request.offset;
  options.delta = request.delta;
  options.all_pairs = request.all_pairs;
  options.max_pairs = request.max_pairs;
  options.Check();
  return options;
}

EvalOutput RunEvaluation(const EvalRequest& request) {
  const TrajectoryPair trajectories = LoadTrajectories(request.inputs);
  const Trajectory& gt = trajectories.gt;
  const Trajectory& est = trajectories.est;
  EvalOutput output;
  if (request.metric == Metric::kAte) {
    const AteResult result = ComputeAte(gt, est, MakeAteOptions(request, trajectories));
    output.text = request.json ? AteToJson(result, gt, est).dump(2) + "\n"
                               : FormatAteReport(result, gt, est, request.rotation);
    if (!request.plot_path.empty()) output.plot = MakeAtePlotData(result, est, request.rotation);
    return output;
  }
  const RpeResult result = ComputeRpe(gt, est, MakeRpeOptions(request, trajectories));
  output.text = request.json ? RpeToJson(result, gt, est).dump(2) + "\n"
                             : FormatRpeReport(result, gt, est, request.rotation);
  if (!request.plot_path.empty()) output.plot = MakeRpePlotData(result, est, request.rotation);
  return output;
}

}  // namespace moslam::eval
