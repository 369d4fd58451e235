// The Python module `moslam` (pybind11): the SLAM system, the evaluator, synthetic sequences and
// mask providers for notebooks and Python programs (docs/RUNNING.md, "Python"). Bad input never
// ends the interpreter: moslam's InputError is moslam.InputError (a ValueError), a wrong array
// type a TypeError, a wrong shape a ValueError, a missing file a FileNotFoundError.
#include <pybind11/pybind11.h>

#include "bindings.h"
#include "moslam/util/error.h"

namespace py = pybind11;

PYBIND11_MODULE(moslam, m) {
  m.doc() = "moslam: movable-object-aware visual SLAM (docs/RUNNING.md, \"Python\")";
  py::register_exception<moslam::InputError>(m, "InputError", PyExc_ValueError);
  moslam::python::BindSystem(m);
  moslam::python::BindEval(m);
  moslam::python::BindData(m);
  moslam::python::BindSegmenter(m);
}
