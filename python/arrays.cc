#include "arrays.h"

#include <cmath>
#include <cstdint>
#include <cstring>

#include <fmt/format.h>

namespace moslam::python {
namespace {

std::string TypeName(const py::handle& object) {
  return py::str(py::type::of(object).attr("__name__")).cast<std::string>();
}

std::string Shape(const py::array& array) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < array.ndim(); ++i) {
    text += (i ? ", " : "") + std::to_string(array.shape(i));
  }
  return text + (array.ndim() == 1 ? ",)" : ")");
}

std::string DtypeName(const py::array& array) { return py::str(array.dtype()).cast<std::string>(); }

// The OpenCV depth of the array's elements, or a TypeError saying what `pixels` takes.
int ElementDepth(const py::array& array, const char* name, Pixels pixels) {
  const bool u8 = py::isinstance<py::array_t<uint8_t>>(array);
  switch (pixels) {
    case Pixels::kImage:
      if (u8) return CV_8U;
      throw py::type_error(fmt::format("{}: expected dtype uint8, got {}", name, DtypeName(array)));
    case Pixels::kDepth:
      if (py::isinstance<py::array_t<uint16_t>>(array)) return CV_16U;
      if (py::isinstance<py::array_t<float>>(array)) return CV_32F;
      throw py::type_error(fmt::format(
          "{}: expected dtype uint16 (DepthMapFactor units) or float32 (metres), got {}", name,
          DtypeName(array)));
    case Pixels::kMask:
      if (u8 || py::isinstance<py::array_t<bool>>(array)) return CV_8U;
      throw py::type_error(
          fmt::format("{}: expected dtype uint8 or bool, got {}", name, DtypeName(array)));
  }
  return CV_8U;
}

// Channels of an (H, W[, C]) array, or a ValueError saying which shapes `pixels` takes.
int Channels(const py::array& array, const char* name, Pixels pixels) {
  const bool image = pixels == Pixels::kImage;
  const auto fail = [&] {
    return py::value_error(
        fmt::format("{}: expected shape {}, got {}", name,
                    image ? "(H, W), (H, W, 1), (H, W, 3) or (H, W, 4)" : "(H, W)", Shape(array)));
  };
  if (array.ndim() == 2) {
    if (array.shape(0) == 0 || array.shape(1) == 0) throw fail();
    return 1;
  }
  if (!image || array.ndim() != 3) throw fail();
  const py::ssize_t c = array.shape(2);
  if (array.shape(0) == 0 || array.shape(1) == 0 || (c != 1 && c != 3 && c != 4)) throw fail();
  return static_cast<int>(c);
}

// Rows of pixels whose channels and columns follow each other, as cv::Mat's rows do.
bool OpenCvLayout(const py::array& array, int channels) {
  const py::ssize_t item = array.itemsize();
  if (!array.attr("flags").attr("aligned").cast<bool>()) return false;
  if (array.ndim() == 3 && array.strides(2) != item) return false;
  if (array.strides(1) != item * channels) return false;
  return array.strides(0) >= array.shape(1) * item * channels;
}

}  // namespace

cv::Mat ToMat(const py::handle& object, const char* name, Pixels pixels, py::object* keep) {
  if (object.is_none()) return cv::Mat();
  if (!py::isinstance<py::array>(object)) {
    throw py::type_error(
        fmt::format("{}: expected a numpy.ndarray, got {}", name, TypeName(object)));
  }
  py::array array = py::reinterpret_borrow<py::array>(object);
  const int depth = ElementDepth(array, name, pixels);
  const int channels = Channels(array, name, pixels);
  if (py::isinstance<py::array_t<bool>>(array)) {
    array = array.attr("view")("uint8").cast<py::array>();  // True is 1: non-zero, as a mask wants
  }
  if (!OpenCvLayout(array, channels)) {
    array = py::module_::import("numpy").attr("ascontiguousarray")(array).cast<py::array>();
  }
  *keep = array;
  return cv::Mat(static_cast<int>(array.shape(0)), static_cast<int>(array.shape(1)),
                 CV_MAKETYPE(depth, channels), const_cast<void*>(array.data()),
                 static_cast<size_t>(array.strides(0)));
}

py::array FromMat(const cv::Mat& mat) {
  const cv::Mat m = mat.isContinuous() ? mat : mat.clone();
  std::vector<py::ssize_t> shape;
  for (int i = 0; i < m.dims; ++i) shape.push_back(m.size[i]);
  if (m.channels() > 1) shape.push_back(m.channels());
  py::dtype dtype;
  switch (m.depth()) {
    case CV_8U:
      dtype = py::dtype::of<uint8_t>();
      break;
    case CV_16U:
      dtype = py::dtype::of<uint16_t>();
      break;
    case CV_32S:
      dtype = py::dtype::of<int32_t>();
      break;
    case CV_32F:
      dtype = py::dtype::of<float>();
      break;
    case CV_64F:
      dtype = py::dtype::of<double>();
      break;
    default:
      throw py::type_error(fmt::format("no NumPy dtype for OpenCV depth {}", m.depth()));
  }
  py::array out(dtype, shape);
  if (m.total() > 0) std::memcpy(out.mutable_data(), m.data, m.total() * m.elemSize());
  return out;
}

py::array_t<double> FromMatrix4d(const Eigen::Matrix4d& m) {
  py::array_t<double> out({4, 4});
  auto a = out.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) a(r, c) = m(r, c);
  }
  return out;
}

py::tuple FromTrajectory(const eval::Trajectory& trajectory) {
  const auto n = static_cast<py::ssize_t>(trajectory.size());
  py::array_t<double> times(n);
  py::array_t<double> poses({n, py::ssize_t{4}, py::ssize_t{4}});
  auto t = times.mutable_unchecked<1>();
  auto p = poses.mutable_unchecked<3>();
  for (py::ssize_t i = 0; i < n; ++i) {
    t(i) = trajectory.has_timestamps() ? trajectory.timestamps[i] : static_cast<double>(i);
    const Eigen::Matrix4d m = trajectory.Matrix(static_cast<size_t>(i));
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) p(i, r, c) = m(r, c);
    }
  }
  return py::make_tuple(times, poses);
}

eval::Trajectory ToTrajectory(const py::handle& times, const py::handle& poses, const char* name) {
  using Doubles = py::array_t<double, py::array::c_style | py::array::forcecast>;
  const auto t = Doubles::ensure(times);
  const auto p = Doubles::ensure(poses);
  if (!t || !p) {
    PyErr_Clear();
    throw py::type_error(fmt::format("{}: expected numeric arrays of times and poses", name));
  }
  if (t.ndim() != 1 || p.ndim() != 3 || p.shape(1) != 4 || p.shape(2) != 4 ||
      p.shape(0) != t.shape(0)) {
    throw py::value_error(
        fmt::format("{}: expected times of shape (N,) and poses of shape (N, 4, 4), got {} and {}",
                    name, Shape(t), Shape(p)));
  }
  eval::Trajectory trajectory;
  trajectory.name = name;
  const auto tt = t.unchecked<1>();
  const auto pp = p.unchecked<3>();
  for (py::ssize_t i = 0; i < t.shape(0); ++i) {
    Eigen::Matrix4d m;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) m(r, c) = pp(i, r, c);
    }
    const Eigen::Matrix3d R = m.topLeftCorner<3, 3>();
    // geometry::SE3 checks this as an invariant (an abort); here it is the caller's input.
    if (!m.allFinite() || !std::isfinite(tt(i)) ||
        !((R * R.transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6) ||
        !(R.determinant() > 0)) {
      throw py::value_error(fmt::format(
          "{}: pose {} is not a rigid transform (finite, rotation block orthonormal)", name, i));
    }
    trajectory.timestamps.push_back(tt(i));
    trajectory.poses.emplace_back(R, m.topRightCorner<3, 1>());
  }
  return trajectory;
}

}  // namespace moslam::python
