// The parts of the Python module `moslam` (module.cc puts them together).
#pragma once

#include <pybind11/pybind11.h>

namespace moslam::python {

namespace py = pybind11;

void BindSystem(py::module_& m);
void BindEval(py::module_& m);  // the submodule moslam.eval
void BindData(py::module_& m);  // synth, read_sequence
void BindSegmenter(py::module_& m);

}  // namespace moslam::python
