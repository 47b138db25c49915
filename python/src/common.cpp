// Shared pieces of the Python bindings (common.hpp).
#include "common.hpp"

#include <map>
#include <mutex>
#include <stdexcept>

#include "vpm/error.hpp"

namespace vpm::python {

Points to_points(const py::handle& values, const char* what) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() != 2 || a.shape(1) != 3)
    throw InputError(std::string(what) + ": expected an (n, 3) array of coordinates");
  Points p(a.shape(0), 3);
  std::copy(a.data(), a.data() + a.size(), p.data());
  return p;
}

Tets to_tets(const py::handle& values, const char* what, Eigen::Index vertices) {
  const auto a = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() != 2 || a.shape(1) != 4)
    throw InputError(std::string(what) + ": expected an (m, 4) array of vertex indices");
  Tets t(a.shape(0), 4);
  const long long* d = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    if (d[i] < 0 || d[i] >= vertices)
      throw InputError(std::string(what) + ": tet " + std::to_string(i / 4) + ": vertex index " + std::to_string(d[i]) +
                       " out of range (" + std::to_string(vertices) + " vertices)");
    t.data()[i] = static_cast<int>(d[i]);
  }
  return t;
}

namespace {

// The vpm.Mesh that `a` is a view of (its base), when `a` starts at `data`.
std::shared_ptr<TetMesh> owner_of(const py::object& a, const void* data_of(const TetMesh&)) {
  if (!py::isinstance<py::array>(a)) return nullptr;
  const py::array arr = a.cast<py::array>();
  const py::object base = arr.base();
  if (!base || !py::isinstance<TetMesh>(base)) return nullptr;
  auto mesh = base.cast<std::shared_ptr<TetMesh>>();
  return arr.data() == data_of(*mesh) ? mesh : nullptr;
}

}  // namespace

std::shared_ptr<TetMesh> mesh_argument(const py::object& vertices, const py::object& tets) {
  if (py::isinstance<TetMesh>(vertices)) {
    if (!tets.is_none()) throw InputError("tets: give a vpm.Mesh alone, or vertices and tets arrays");
    return vertices.cast<std::shared_ptr<TetMesh>>();
  }
  if (tets.is_none()) throw InputError("tets: missing (give a vpm.Mesh, or vertices and tets arrays)");
  const auto mv = owner_of(vertices, [](const TetMesh& m) -> const void* { return m.vertices.data(); });
  const auto mt = owner_of(tets, [](const TetMesh& m) -> const void* { return m.tets.data(); });
  if (mv && mv == mt) return mv;  // both arrays are one vpm.Mesh's own: no copy
  auto mesh = std::make_shared<TetMesh>();
  mesh->vertices = to_points(vertices, "vertices");
  mesh->tets = to_tets(tets, "tets", mesh->vertices.rows());
  return mesh;
}

std::function<void(const std::string&)> Progress::function() {
  if (callback_.is_none()) return {};
  return [this](const std::string& line) {
    py::gil_scoped_acquire gil;
    if (error_) throw std::runtime_error("stopped by the progress callback");
    try {
      if (PyErr_CheckSignals() != 0) throw py::error_already_set();
      callback_(line);
    } catch (py::error_already_set& e) {
      error_ = std::make_shared<py::error_already_set>(std::move(e));
      throw std::runtime_error("stopped by the progress callback");
    }
  };
}

void Progress::rethrow() {
  if (!error_) return;
  auto e = std::move(error_);
  error_.reset();
  throw std::move(*e);
}

}  // namespace vpm::python
