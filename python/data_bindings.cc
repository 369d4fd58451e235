// moslam.synth, moslam.read_sequence and moslam.Segmenter: data in and masks out.
#include <optional>
#include <string>
#include <utility>

#include <pybind11/stl.h>

#include "arrays.h"
#include "bindings.h"
#include "moslam/api/segmenter.h"
#include "moslam/io/dataset.h"
#include "moslam/synth/generator.h"

namespace moslam::python {
namespace {

std::string Synth(const std::string& out, const std::string& preset, int frames, uint64_t seed,
                  int width, int height, bool sensor_noise) {
  synth::GeneratorOptions options;
  options.out = out;
  options.preset = preset;
  options.frames = frames;
  options.seed = seed;
  options.width = width;
  options.height = height;
  options.sensor_noise = sensor_noise;
  options.progress = false;
  options.Check();
  py::gil_scoped_release release;
  synth::GenerateSequence(options);
  return out;
}

py::dict ReadSequence(const std::string& path) {
  const io::Sequence sequence = io::ReadDataset(path);
  py::list frames;
  for (const io::FrameEntry& f : sequence.frames) {
    py::dict frame;
    frame["timestamp"] = f.timestamp;
    frame["image"] = f.image_left;
    frame["right"] = f.image_right.empty() ? py::object(py::none()) : py::str(f.image_right);
    frame["depth"] = f.depth.empty() ? py::object(py::none()) : py::str(f.depth);
    frames.append(frame);
  }
  py::dict d;
  d["name"] = sequence.name;
  d["sensor"] = io::ToString(sequence.sensor);
  d["frames"] = frames;
  d["ground_truth"] = sequence.ground_truth_path;
  return d;
}

py::tuple Segment(api::Segmenter& segmenter, const py::object& image, const py::object& depth) {
  py::object keep_image, keep_depth;
  const cv::Mat image_mat = ToMat(image, "image", Pixels::kImage, &keep_image);
  const cv::Mat depth_mat = ToMat(depth, "depth", Pixels::kDepth, &keep_depth);
  if (image_mat.empty()) throw py::value_error("segment: image is None");
  if (!depth_mat.empty() && depth_mat.type() != CV_32FC1) {
    throw py::type_error("segment: depth must be float32 metres");
  }
  api::Segmentation result;
  {
    py::gil_scoped_release release;
    result = segmenter.Segment(image_mat, depth_mat);
  }
  return py::make_tuple(FromMat(result.probabilities), FromMat(result.mask));
}

}  // namespace

void BindData(py::module_& m) {
  m.def("synth", &Synth, py::arg("out"), py::arg("preset") = "w_xyz", py::arg("frames") = 30,
        py::arg("seed") = 1, py::arg("width") = 0, py::arg("height") = 0,
        py::arg("sensor_noise") = true,
        R"(Renders a synthetic sequence with exact ground truth into `out` (as `moslam synth`;
docs/SYNTH.md): TUM RGB-D layout (rgb.txt, depth.txt, groundtruth.txt, settings.yaml) for the
indoor presets, KITTI for the street ones. width/height 0: the preset's. Returns `out`.)");
  m.def("read_sequence", &ReadSequence, py::arg("path"),
        R"(The frames of a data-set folder (TUM RGB-D, KITTI, EuRoC) as `moslam run` reads them:
a dict with name, sensor, ground_truth (path or None) and frames, each a dict of timestamp,
image, right and depth paths.)");
}

void BindSegmenter(py::module_& m) {
  py::class_<api::Segmenter>(m, "Segmenter", R"(Movable-object masks from a model card.

Segmenter(model_card): an ONNX segmentation or detector card (configs/models/*.yaml; model files
beside it or under MOSLAM_SHARED). segment(image, depth=None) -> (probabilities, mask).)")
      .def(py::init<const std::string&>(), py::arg("model_card"),
           py::call_guard<py::gil_scoped_release>())
      .def("segment", &Segment, py::arg("image"), py::arg("depth") = py::none(),
           "(probabilities (classes, h, w) float32 at the network's size, mask (H, W) uint8 "
           "255 = movable)")
      .def_property_readonly("classes", &api::Segmenter::classes)
      .def_property_readonly("movable", &api::Segmenter::movable)
      .def("__repr__",
           [](const api::Segmenter& s) { return "<moslam.Segmenter " + s.Describe() + ">"; });
}

}  // namespace moslam::python
