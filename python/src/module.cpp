// The compiled part of the Python package `vpm` (vpm._vpm): the library's types and calls.
// The pure-Python part (python/vpm/__init__.py) adds the conveniences (paths, nibabel images,
// tqdm) and the documented signatures.
#include "common.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"

namespace py = pybind11;

PYBIND11_MODULE(_vpm, m) {
  m.doc() = "vpm: volume-preserving mapping and registration of 3-D shapes to the unit ball (compiled part)";
  // library errors keep their messages: InputError -> ValueError, NumericalError -> vpm.NumericalError
  static py::exception<vpm::NumericalError> numerical(m, "NumericalError", PyExc_RuntimeError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const vpm::InputError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const vpm::NumericalError& e) {
      PyErr_SetString(numerical.ptr(), e.what());
    }
  });
  vpm::python::bind_device(m);
  vpm::python::bind_mesh(m);
  vpm::python::bind_image(m);
  vpm::python::bind_map(m);
  vpm::python::bind_surface(m);
  vpm::python::bind_register(m);
  vpm::python::bind_collective(m);
  m.attr("__version__") = VPM_VERSION;
}
