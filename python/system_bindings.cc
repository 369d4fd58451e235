// moslam.System: api::Slam for Python (python/README in docs/RUNNING.md).
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "moslam/api/slam.h"

namespace moslam::python {
namespace {

api::Sensor ParseSensor(const std::string& name) {
  const std::optional<io::SensorType> sensor = io::ParseSensorType(name);
  if (!sensor) {
    throw py::value_error(
        fmt::format("sensor: '{}' is none of 'monocular', 'stereo', 'rgbd'", name));
  }
  return *sensor;
}

// A missing file is the FileNotFoundError Python programs expect, not an InputError.
void RequireFile(const std::optional<std::string>& path, const char* name) {
  if (!path) return;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(*path, ec)) {
    PyErr_SetObject(PyExc_FileNotFoundError,
                    py::make_tuple(2, fmt::format("{}: no file '{}'", name, *path), *path).ptr());
    throw py::error_already_set();
  }
}

std::unique_ptr<api::Slam> MakeSlam(const std::string& settings,
                                    const std::optional<std::string>& vocabulary,
                                    const std::string& sensor,
                                    const std::optional<std::string>& model_card,
                                    bool deterministic) {
  RequireFile(settings, "settings");
  RequireFile(vocabulary, "vocabulary");
  RequireFile(model_card, "model_card");
  api::SlamOptions options;
  options.settings = settings;
  options.vocabulary = vocabulary.value_or("");
  options.sensor = ParseSensor(sensor);
  options.model_card = model_card.value_or("");
  options.deterministic = deterministic;
  py::gil_scoped_release release;  // the vocabulary takes a while to load
  return std::make_unique<api::Slam>(options);
}

py::tuple Result(const api::Tracked& t) {
  py::object pose = py::none();
  if (t.T_world_cam) pose = FromMatrix4d(*t.T_world_cam);
  return py::make_tuple(pose, slam::ToString(t.state));
}

// The frame's arrays seen in place (arrays.h), tracked without the GIL.
py::tuple Track(api::Slam& slam, double timestamp, const py::object& image, const py::object& depth,
                const py::object& right, const py::object& mask) {
  py::object keep_image, keep_depth, keep_right, keep_mask;
  const cv::Mat image_mat = ToMat(image, "image", Pixels::kImage, &keep_image);
  const cv::Mat depth_mat = ToMat(depth, "depth", Pixels::kDepth, &keep_depth);
  const cv::Mat right_mat = ToMat(right, "right", Pixels::kImage, &keep_right);
  const cv::Mat mask_mat = ToMat(mask, "mask", Pixels::kMask, &keep_mask);
  const char* sensor = io::ToString(slam.sensor());
  const auto require = [&](bool ok, const char* what) {
    if (!ok) throw py::value_error(fmt::format("track: a {} system {}", sensor, what));
  };
  if (image_mat.empty()) throw py::value_error("track: image is None");
  require(!depth_mat.empty() == (slam.sensor() == api::Sensor::kRgbD),
          slam.sensor() == api::Sensor::kRgbD ? "needs depth=" : "takes no depth=");
  require(!right_mat.empty() == (slam.sensor() == api::Sensor::kStereo),
          slam.sensor() == api::Sensor::kStereo ? "needs right=" : "takes no right=");
  api::Tracked tracked;
  {
    py::gil_scoped_release release;
    switch (slam.sensor()) {
      case api::Sensor::kMonocular:
        tracked = slam.TrackMonocular(timestamp, image_mat, mask_mat);
        break;
      case api::Sensor::kStereo:
        tracked = slam.TrackStereo(timestamp, image_mat, right_mat, mask_mat);
        break;
      case api::Sensor::kRgbD:
        tracked = slam.TrackRgbD(timestamp, image_mat, depth_mat, mask_mat);
        break;
    }
  }
  return Result(tracked);
}

py::dict Summary(const api::Slam& slam) {
  const slam::MapSummary s = slam.Summary();
  py::dict d;
  d["frames"] = slam.frames();
  d["keyframes"] = s.keyframes;
  d["map_points"] = s.map_points;
  d["lost_frames"] = s.lost_frames;
  d["relocalizations"] = s.relocalizations;
  d["loops_closed"] = s.loops_closed;
  d["initialized_frame"] = s.initialized_frame;
  return d;
}

py::array_t<double> MapPoints(const api::Slam& slam) {
  const std::vector<Eigen::Vector3d> points = slam.MapPoints();
  py::array_t<double> out({static_cast<py::ssize_t>(points.size()), py::ssize_t{3}});
  auto a = out.mutable_unchecked<2>();
  for (size_t i = 0; i < points.size(); ++i) {
    for (int k = 0; k < 3; ++k) a(static_cast<py::ssize_t>(i), k) = points[i](k);
  }
  return out;
}

}  // namespace

void BindSystem(py::module_& m) {
  py::class_<api::Slam>(m, "System", R"(A SLAM system (moslam/moslam.h's api::Slam).

System(settings, vocabulary=None, sensor="rgbd", model_card=None, deterministic=False)

settings: ORB-SLAM2 settings YAML; vocabulary: e.g. data/vocab/moslam_orb.mvoc (None: no
relocalization or loop closing); sensor: "monocular", "stereo" or "rgbd"; model_card: a
segmentation/detector card whose network masks every frame given no mask; deterministic: as
`moslam run --deterministic`.)")
      .def(py::init(&MakeSlam), py::arg("settings"), py::arg("vocabulary") = py::none(),
           py::arg("sensor") = "rgbd", py::arg("model_card") = py::none(),
           py::arg("deterministic") = false)
      .def("track", &Track, py::arg("timestamp"), py::arg("image"), py::arg("depth") = py::none(),
           py::arg("right") = py::none(), py::arg("mask") = py::none(),
           R"(Tracks one frame; returns (pose, state): pose the 4x4 float64 T_world_cam or None,
state "ok", "lost" or "not_initialized".

image: uint8 (H, W) grey or (H, W, 3|4) colour in the settings' Camera.RGB order (cv2.imread's
BGR for the TUM files); depth (rgbd): uint16 in DepthMapFactor units or float32 metres;
right (stereo): the right image; mask: uint8/bool (H, W), non-zero = movable. Arrays laid out
as OpenCV's are read in place, not copied.)")
      .def("finish", &api::Slam::Finish, py::call_guard<py::gil_scoped_release>(),
           "Waits for mapping to finish; no frame can be tracked after it.")
      .def(
          "trajectory", [](const api::Slam& s) { return FromTrajectory(s.Trajectory()); },
          "(times (N,), poses (N, 4, 4)) of every tracked frame, T_world_cam.")
      .def(
          "keyframe_trajectory",
          [](const api::Slam& s) { return FromTrajectory(s.KeyFrameTrajectory()); },
          "(times (N,), poses (N, 4, 4)) of the keyframes.")
      .def("map_points", &MapPoints, "(N, 3) float64 world positions of the map points.")
      .def("summary", &Summary, "Counts: frames, keyframes, map points, lost frames, loops.")
      .def("save_map", &api::Slam::SaveMap, py::arg("path"),
           py::call_guard<py::gil_scoped_release>(), "Finishes, then writes the map file.")
      .def_property_readonly("sensor", [](const api::Slam& s) { return io::ToString(s.sensor()); })
      .def_property_readonly("frames", &api::Slam::frames);
}

}  // namespace moslam::python
