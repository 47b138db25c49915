// Shared pieces of the Python bindings: arrays handed to NumPy without copies, arrays read from
// NumPy, the device a call runs on, progress callbacks into Python, and the binders of each area.
#pragma once
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <exception>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "vpm/device.hpp"
#include "vpm/mesh.hpp"

namespace vpm::python {

namespace py = pybind11;

/// A C++ matrix (row-major, or a vector) handed to NumPy without a copy: moved to the heap and
/// owned by a capsule that the array keeps alive.
template <class M>
py::array owned_array(M&& matrix) {
  using T = std::decay_t<M>;
  using S = typename T::Scalar;
  auto* heap = new T(std::forward<M>(matrix));
  py::capsule owner(heap, [](void* p) { delete static_cast<T*>(p); });
  if constexpr (T::ColsAtCompileTime == 1)
    return py::array_t<S>({heap->rows()}, {static_cast<py::ssize_t>(sizeof(S))}, heap->data(), owner);
  else
    return py::array_t<S>({heap->rows(), heap->cols()},
                          {static_cast<py::ssize_t>(heap->cols() * sizeof(S)), static_cast<py::ssize_t>(sizeof(S))},
                          heap->data(), owner);
}

/// A writable NumPy view of `rows` x `cols` values at `data` (row-major), kept alive by `base`.
template <class S>
py::array view_array(S* data, py::ssize_t rows, py::ssize_t cols, py::handle base) {
  return py::array_t<S>({rows, cols}, {static_cast<py::ssize_t>(cols * sizeof(S)), static_cast<py::ssize_t>(sizeof(S))},
                        data, base);
}

/// (n, 3) float array-like -> Points (one copy into the library's layout). ValueError naming
/// `what` for another shape.
Points to_points(const py::handle& values, const char* what);
/// (m, 4) integer array-like -> Tets (indices checked against `vertices`).
Tets to_tets(const py::handle& values, const char* what, Eigen::Index vertices);

/// The mesh a call works on: a vpm.Mesh as it is, or its own arrays (no copy: `vertices` and
/// `tets` views of one vpm.Mesh), else a new mesh copied from the arrays.
std::shared_ptr<TetMesh> mesh_argument(const py::object& vertices, const py::object& tets);

/// The device named by `spec` (None: the one select_device() chose, else VPM_DEVICE's).
std::shared_ptr<Device> device_for(const std::optional<std::string>& spec);

/// A progress callback for the library, callable from any thread: takes the GIL, calls
/// `callback(line)`, and when the callback raises (or Ctrl-C was pressed) stops the library's work
/// by throwing; rethrow() then raises the Python error in the caller.
class Progress {
 public:
  explicit Progress(py::object callback) : callback_(std::move(callback)) {}
  std::function<void(const std::string&)> function();
  /// Raises the callback's error, if it raised (call with the GIL held).
  void rethrow();
  bool active() const { return !callback_.is_none(); }

 private:
  py::object callback_;
  std::shared_ptr<py::error_already_set> error_;
};

/// Runs `work` without the GIL, then raises the progress callback's error if there was one.
template <class F>
auto without_gil(Progress* progress, F&& work) {
  try {
    py::gil_scoped_release release;
    return work();
  } catch (...) {
    if (progress) progress->rethrow();
    throw;
  }
}

void bind_device(py::module_& m);
void bind_mesh(py::module_& m);
void bind_image(py::module_& m);
void bind_map(py::module_& m);
void bind_register(py::module_& m);
void bind_collective(py::module_& m);
void bind_surface(py::module_& m);

}  // namespace vpm::python
