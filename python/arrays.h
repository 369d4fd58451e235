// NumPy arrays to and from OpenCV and Eigen for the Python module: images, depth maps and masks
// are seen in place (a cv::Mat header over the array's memory) when their rows are laid out as
// OpenCV's, so a frame is not copied on its way to tracking; poses come back as 4x4 float64
// arrays. A wrong type is a TypeError, a wrong shape a ValueError, each naming the argument.
#pragma once

#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "moslam/eval/trajectory.h"

namespace moslam::python {

namespace py = pybind11;

// What an argument may hold.
enum class Pixels {
  kImage,  // uint8 (H, W), (H, W, 1), (H, W, 3) or (H, W, 4)
  kDepth,  // uint16 (H, W) in the settings' DepthMapFactor units, or float32 (H, W) metres
  kMask,   // uint8 or bool (H, W), non-zero = movable
};

// The array as a cv::Mat: a view of its memory when the layout allows (each pixel's channels
// adjacent, pixels adjacent in a row, rows any distance apart), else of a contiguous copy. `keep`
// holds whatever the Mat points into; it must outlive the Mat. None gives an empty Mat.
cv::Mat ToMat(const py::handle& object, const char* name, Pixels pixels, py::object* keep);

// A (H, W[, C]) array holding a copy of the Mat's pixels.
py::array FromMat(const cv::Mat& mat);

py::array_t<double> FromMatrix4d(const Eigen::Matrix4d& m);
// (N,) float64 timestamps and (N, 4, 4) float64 poses T_world_cam.
py::tuple FromTrajectory(const eval::Trajectory& trajectory);
// The inverse, checked: shapes, finite values, a rotation block that is a rotation.
eval::Trajectory ToTrajectory(const py::handle& times, const py::handle& poses, const char* name);

}  // namespace moslam::python
