// Trajectory figure for `moslam eval --plot FILE.png|svg`.
//
// One image shows (1) a top view of ground truth and aligned estimate on the two axes with the
// largest extent, equal aspect, the estimate coloured by its per-pose error; (2) x, y and z over
// time, reference against estimate; (3) the error over time with its RMSE. The same layout is
// rendered either as a raster PNG (OpenCV) or as an SVG text file.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace moslam::eval {

struct TrajectoryPlotData {
  std::string title;                       // e.g. "ATE, SE(3)-aligned: fr2_desk_ORB.txt"
  std::vector<double> times;               // seconds (or frame index), one per compared pose
  std::vector<Eigen::Vector3d> reference;  // ground-truth positions
  std::vector<Eigen::Vector3d> estimate;   // aligned estimate positions, same length
  // Per-pose error (ATE) or per-pair error (RPE). When shorter than `times`, error i is drawn at
  // times[i] (the first pose of pair i) and the top view is not coloured by it.
  std::vector<double> errors;
  std::string error_label;  // e.g. "ATE [m]" or "RPE trans. [m]"
  // Label of the time axes: what `times` holds (KITTI files have frame indices, not seconds).
  std::string time_label = "time since start [s]";
};

// Writes a figure to `path`; the format follows the extension: .png (raster, via OpenCV) or
// .svg (vector, written as text). Throws InputError for another extension, inconsistent
// lengths, or a path that cannot be written. Non-finite values are skipped (lines break there).
void WriteTrajectoryPlot(const TrajectoryPlotData& data, const std::string& path);

}  // namespace moslam::eval
