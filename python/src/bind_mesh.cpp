// vpm.Mesh (the library's TetMesh, its arrays shared with NumPy), read_mesh, write_mesh, validate.
#include <cstdint>

#include "common.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/validate.hpp"

namespace vpm::python {
namespace {

py::dict fields(const py::object& self, bool cells) {
  auto& mesh = self.cast<TetMesh&>();
  py::dict out;
  for (Field& f : cells ? mesh.cell_data : mesh.point_data) {
    py::array a = view_array(f.values.data(), f.values.rows(), f.values.cols(), self);
    out[py::str(f.name)] = f.values.cols() == 1 ? a.attr("reshape")(f.values.rows()) : a;
  }
  return out;
}

void set_field(TetMesh& mesh, const std::string& name, const py::handle& values, bool integer, bool cells) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() < 1 || a.ndim() > 2) throw InputError(name + ": expected a 1-D or 2-D array");
  const Eigen::Index rows = a.shape(0), cols = a.ndim() == 2 ? a.shape(1) : 1;
  const Eigen::Index want = cells ? mesh.num_tets() : mesh.num_vertices();
  if (rows != want)
    throw InputError(name + ": " + std::to_string(rows) + " rows for " + std::to_string(want) + (cells ? " tets" : " vertices"));
  FieldValues v(rows, cols);
  std::copy(a.data(), a.data() + a.size(), v.data());
  if (cells) mesh.set_cell_field(name, std::move(v), integer);
  else mesh.set_point_field(name, std::move(v), integer);
}

void bind_mesh_type(py::module_& m) {
  py::class_<TetMesh, std::shared_ptr<TetMesh>> mesh(m, "Mesh", R"(A tetrahedral mesh: vertices, tets and named point and cell fields.

Mesh(vertices, tets, point_data=None, cell_data=None) copies the arrays once into the library's
layout. The attributes `vertices` ((n, 3) float64), `tets` ((m, 4) int32) and the arrays in
`point_data` / `cell_data` are NumPy views of the mesh's own memory: reading them copies
nothing, writing into them changes the mesh, and passing them (or the mesh) back to vpm copies
nothing either.)");
  mesh.def(py::init([](const py::object& vertices, const py::object& tets, const py::object& point_data,
                       const py::object& cell_data) {
             auto m = std::make_shared<TetMesh>();
             m->vertices = to_points(vertices, "vertices");
             m->tets = to_tets(tets, "tets", m->vertices.rows());
             if (!point_data.is_none())
               for (auto [k, v] : point_data.cast<py::dict>()) set_field(*m, k.cast<std::string>(), v, false, false);
             if (!cell_data.is_none())
               for (auto [k, v] : cell_data.cast<py::dict>()) set_field(*m, k.cast<std::string>(), v, false, true);
             return m;
           }),
           py::arg("vertices"), py::arg("tets"), py::arg("point_data") = py::none(), py::arg("cell_data") = py::none());
  mesh.def_property(
      "vertices",
      [](const py::object& self) {
        auto& m = self.cast<TetMesh&>();
        return view_array(m.vertices.data(), m.vertices.rows(), 3, self);
      },
      [](TetMesh& m, const py::object& v) {
        Points p = to_points(v, "vertices");
        if (p.rows() != m.vertices.rows())
          throw InputError("vertices: " + std::to_string(p.rows()) + " rows for a mesh of " +
                           std::to_string(m.vertices.rows()) + " vertices");
        m.vertices = std::move(p);
      },
      "(n, 3) float64 view of the vertex positions.");
  mesh.def_property_readonly(
      "tets",
      [](const py::object& self) {
        auto& m = self.cast<TetMesh&>();
        return view_array(m.tets.data(), m.tets.rows(), 4, self);
      },
      "(m, 4) int32 view of the tets' vertex indices (0-based).");
  mesh.def_property_readonly("num_vertices", &TetMesh::num_vertices);
  mesh.def_property_readonly("num_tets", &TetMesh::num_tets);
  mesh.def_property_readonly(
      "point_data", [](const py::object& self) { return fields(self, false); },
      "{name: view} of the point fields ((n,) or (n, k) float64), e.g. original_position, vertex_volume_ratio, label.");
  mesh.def_property_readonly(
      "cell_data", [](const py::object& self) { return fields(self, true); },
      "{name: view} of the cell fields ((m,) or (m, k) float64), e.g. tet_volume_ratio, label.");
  mesh.def(
      "set_point_field",
      [](TetMesh& m, const std::string& name, const py::object& v, bool integer) { set_field(m, name, v, integer, false); },
      py::arg("name"), py::arg("values"), py::arg("integer") = false, "Adds or replaces a point field (copied).");
  mesh.def(
      "set_cell_field",
      [](TetMesh& m, const std::string& name, const py::object& v, bool integer) { set_field(m, name, v, integer, true); },
      py::arg("name"), py::arg("values"), py::arg("integer") = false, "Adds or replaces a cell field (copied).");
  mesh.def("copy", [](const TetMesh& m) { return std::make_shared<TetMesh>(m); }, "A deep copy.");
  mesh.def("__repr__", [](const TetMesh& m) {
    std::string f;
    for (const auto& x : m.point_data) f += (f.empty() ? "" : ", ") + x.name;
    for (const auto& x : m.cell_data) f += (f.empty() ? "" : ", ") + x.name + " (cells)";
    return "<vpm.Mesh " + std::to_string(m.num_vertices()) + " vertices, " + std::to_string(m.num_tets()) + " tets" +
           (f.empty() ? "" : "; fields " + f) + ">";
  });
}

}  // namespace

void bind_mesh(py::module_& m) {
  bind_mesh_type(m);

  m.def(
      "_mesh_addresses",
      [](const py::object& vertices, const py::object& tets) {
        const auto mesh = mesh_argument(vertices, tets);
        return py::make_tuple(reinterpret_cast<std::uintptr_t>(mesh->vertices.data()),
                              reinterpret_cast<std::uintptr_t>(mesh->tets.data()));
      },
      py::arg("vertices"), py::arg("tets") = py::none(),
      "Where the mesh a call would work on keeps its vertices and tets (addresses): equal to the\n"
      "arrays' own when they pass without a copy (tests and bench/python measure it).");
  m.def(
      "read_mesh",
      [](const std::string& path) {
        py::gil_scoped_release release;
        return std::make_shared<TetMesh>(read_mesh(path));
      },
      py::arg("path"),
      "Reads a tet mesh (.vtu, .mesh, .msh, .node/.ele), its fields too. ValueError naming the file\n"
      "and line for a malformed file.");
  m.def(
      "write_mesh",
      [](const std::string& path, std::shared_ptr<TetMesh> mesh, bool ascii) {
        py::gil_scoped_release release;
        write_mesh(path, *mesh, ascii ? VtuEncoding::ascii : VtuEncoding::binary);
      },
      py::arg("path"), py::arg("mesh"), py::arg("ascii") = false,
      "Writes a tet mesh, format by extension (.vtu carries every field); written under a\n"
      "temporary name and renamed, so a failure leaves no partial file.");
  m.def(
      "validate",
      [](std::shared_ptr<TetMesh> mesh, const std::string& source) {
        ValidationReport r;
        {
          py::gil_scoped_release release;
          r = validate_mesh(*mesh, source);
        }
        py::dict d;
        d["reoriented_tets"] = r.reoriented_tets;
        d["boundary_faces"] = r.boundary_faces;
        d["boundary_vertices"] = r.boundary_vertices;
        d["boundary_euler"] = r.boundary_euler;
        d["min_dihedral_deg"] = r.min_dihedral_deg;
        d["sliver_tets"] = r.sliver_tets;
        return d;
      },
      py::arg("mesh"), py::arg("source") = "mesh",
      "Checks that the mesh is a valid solid ball (one closed genus-0 boundary, no degenerate or\n"
      "duplicate tet) and turns negatively oriented tets in place. ValueError naming `source`\n"
      "and the element otherwise; returns the input quality.");
}

}  // namespace vpm::python
