// TEMPORARY stand-in for the trajectory plot (written in parallel on another branch); replaced
// wholesale at merge. Keep this file and plot.cc trivial.
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
  std::vector<double> errors;  // per-pose error (ATE) or per-pair error (RPE, may be shorter)
  std::string error_label;     // e.g. "ATE [m]" or "RPE trans. [m]"
};

void WriteTrajectoryPlot(const TrajectoryPlotData& data, const std::string& path);  // .png/.svg

}  // namespace moslam::eval
