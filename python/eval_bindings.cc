// moslam.eval: ATE and RPE on arrays, trajectory files (the evaluator of `moslam eval`).
#include <optional>
#include <string>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "moslam/eval/evaluate.h"
#include "moslam/eval/trajectory_io.h"

namespace moslam::python {
namespace {

py::dict Statistics(const eval::ErrorStatistics& s) {
  py::dict d;
  d["count"] = s.count;
  d["rmse"] = s.rmse;
  d["mean"] = s.mean;
  d["median"] = s.median;
  d["std"] = s.std;
  d["min"] = s.min;
  d["max"] = s.max;
  return d;
}

// Translation statistics at the top level (the ATE people quote), rotation beside them.
template <typename Result>
py::dict Report(const Result& result) {
  py::dict d = Statistics(result.translation.stats);
  d["rotation_deg"] = Statistics(result.rotation.stats);
  d["alignment"] = FromMatrix4d(result.alignment.Matrix());
  return d;
}

eval::TrajectoryPair Pair(const py::handle& gt_times, const py::handle& gt_poses,
                          const py::handle& est_times, const py::handle& est_poses) {
  return {ToTrajectory(gt_times, gt_poses, "ground truth"),
          ToTrajectory(est_times, est_poses, "estimate")};
}

py::dict Ate(const py::handle& gt_times, const py::handle& gt_poses, const py::handle& est_times,
             const py::handle& est_poses, const std::string& alignment,
             const std::string& convention, std::optional<double> max_dt) {
  const eval::TrajectoryPair pair = Pair(gt_times, gt_poses, est_times, est_poses);
  eval::EvalRequest request;  // `moslam eval ate`'s defaults, as `moslam run` uses them
  request.convention = convention;
  request.alignment = alignment;
  request.max_dt = max_dt;
  const eval::AteOptions options = eval::MakeAteOptions(request, pair);
  return Report(eval::ComputeAte(pair.gt, pair.est, options));
}

py::dict Rpe(const py::handle& gt_times, const py::handle& gt_poses, const py::handle& est_times,
             const py::handle& est_poses, double delta, std::optional<std::string> delta_unit,
             const std::string& convention, std::optional<double> max_dt) {
  const eval::TrajectoryPair pair = Pair(gt_times, gt_poses, est_times, est_poses);
  eval::EvalRequest request;
  request.metric = eval::Metric::kRpe;
  request.convention = convention;
  request.delta = delta;
  request.delta_unit = delta_unit;
  request.max_dt = max_dt;
  const eval::RpeOptions options = eval::MakeRpeOptions(request, pair);
  return Report(eval::ComputeRpe(pair.gt, pair.est, options));
}

}  // namespace

void BindEval(py::module_& m) {
  py::module_ e = m.def_submodule("eval", "Trajectory errors (ATE, RPE) as `moslam eval` computes");
  e.def("ate", &Ate, py::arg("gt_times"), py::arg("gt_poses"), py::arg("est_times"),
        py::arg("est_poses"), py::arg("alignment") = "se3", py::arg("convention") = "tum",
        py::arg("max_dt") = py::none(),
        R"(Absolute trajectory error of an estimate against ground truth.

Times (N,) in seconds, poses (N, 4, 4) T_world_cam. alignment: se3, sim3 (monocular) or none;
convention: tum (evaluate_ate.py) or evo. Returns a dict: rmse, mean, median, std, min, max (m),
count, rotation_deg (the same statistics in degrees) and alignment (4x4, S_gt_est).)");
  e.def("rpe", &Rpe, py::arg("gt_times"), py::arg("gt_poses"), py::arg("est_times"),
        py::arg("est_poses"), py::arg("delta") = 1.0, py::arg("delta_unit") = py::none(),
        py::arg("convention") = "tum", py::arg("max_dt") = py::none(),
        "Relative pose error over `delta` (s for tum, frames for evo): a dict as ate's.");
  e.def(
      "read_trajectory",
      [](const std::string& path, const std::string& format) {
        return FromTrajectory(eval::ReadTrajectory(path, eval::ParseTrajectoryFormat(format)));
      },
      py::arg("path"), py::arg("format") = "auto",
      "(times (N,), poses (N, 4, 4)) from a TUM, KITTI or EuRoC trajectory file (format: auto, "
      "tum, kitti, euroc); KITTI files without times give the indices.");
  e.def(
      "write_tum",
      [](const std::string& path, const py::handle& times, const py::handle& poses) {
        eval::WriteTum(ToTrajectory(times, poses, "trajectory"), path);
      },
      py::arg("path"), py::arg("times"), py::arg("poses"),
      "Writes a TUM trajectory file (every digit of each number kept).");
}

}  // namespace moslam::python
