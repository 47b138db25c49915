// Medit .mesh (ASCII, the INRIA "libMeshb" text form): keyword sections, free-form tokens,
// '#' comments, 1-based indices. Reads Vertices and Tetrahedra (the tet reference becomes the
// cell field `label` unless all references are 0); known sections of other entities are
// skipped. Writes MeshVersionFormatted 2 (double precision), Vertices, Tetrahedra (label as
// reference) and the boundary Triangles (reference 0) for viewers.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"
#include "vpm/topology.hpp"

namespace vpm::detail {

namespace {

// Sections we skip: keyword -> integers per entry (indices + reference).
const std::map<std::string, int>& skipped_sections() {
  static const std::map<std::string, int> m = {
      {"edges", 3},          {"triangles", 4},       {"quadrilaterals", 5},
      {"hexahedra", 9},      {"prisms", 7},          {"pyramids", 6},
      {"corners", 1},        {"ridges", 1},          {"requiredvertices", 1},
      {"requirededges", 1},  {"requiredtriangles", 1}, {"normals", 3},
      {"tangents", 3},       {"normalatvertices", 2}, {"tangentatvertices", 2},
      {"normalattrianglevertices", 3}, {"geometry", 0}, {"identifier", 0}};
  return m;
}

std::string lower(std::string_view s) {
  std::string r(s);
  for (auto& c : r) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return r;
}

// Vertices: "n", then n lines "x y z reference" (the reference is dropped).
void read_vertices(Scanner& s, TetMesh& mesh) {
  const int n = s.need_count("the number of Vertices");
  s.check_fits(n, 4, "vertices");
  mesh.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    auto what = [&] { return "vertex " + std::to_string(i + 1) + " of " + std::to_string(n); };
    for (int k = 0; k < 3; ++k) mesh.vertices(i, k) = s.to_real(s.need_lazy(what), "a vertex coordinate");
    s.to_int(s.need_lazy(what), "a vertex reference");
  }
}

// Tetrahedra: "m", then m lines "v1 v2 v3 v4 reference" (1-based); indices are range-checked
// here when the Vertices came first.
void read_tetrahedra(Scanner& s, TetMesh& mesh, bool have_vertices, FieldValues& refs) {
  const int m = s.need_count("the number of Tetrahedra");
  s.check_fits(m, 5, "tetrahedra");
  refs.resize(m, 1);
  mesh.tets.resize(m, 4);
  for (int i = 0; i < m; ++i) {
    for (int k = 0; k < 4; ++k) {
      const long long v = s.to_int(s.need_lazy([&] {
        return "tetrahedron " + std::to_string(i + 1) + " of " + std::to_string(m);
      }), "a vertex index");
      if (v < 1 || (have_vertices && v > mesh.vertices.rows())) {
        std::string why = "tetrahedron " + std::to_string(i + 1) + ": vertex index " +
                          std::to_string(v) + " out of range 1.." +
                          (have_vertices ? std::to_string(mesh.vertices.rows()) : "n");
        if (v == 0) why += " (Medit indices are 1-based; the file looks 0-based)";
        s.fail(why);
      }
      mesh.tets(i, k) = static_cast<int>(v - 1);
    }
    refs(i, 0) = static_cast<double>(s.to_int(
        s.need_lazy([&] { return "the reference of tetrahedron " + std::to_string(i + 1); }),
        "a tetrahedron reference"));
  }
}

// A section of other entities: "k", then k entries of `per` numbers, checked and dropped.
void skip_entries(Scanner& s, std::string_view keyword, int per) {
  const std::string name(keyword);
  const int k = s.need_count("the number of " + name);
  s.check_fits(static_cast<long long>(k) * per, 1, "values in " + name);
  const std::string what = name + " entries";
  for (long long i = 0; i < static_cast<long long>(k) * per; ++i)
    s.to_real(s.need_lazy([&] { return "entry " + std::to_string(i / per + 1) + " of " + name; }), what);
}

// Tetrahedra read before Vertices: their indices are range-checked now, at the Tetrahedra line.
void check_late_indices(const Scanner& s, const TetMesh& mesh, size_t tets_line) {
  for (Eigen::Index i = 0; i < mesh.tets.rows(); ++i)
    for (int k = 0; k < 4; ++k)
      if (mesh.tets(i, k) >= mesh.vertices.rows())
        s.fail_at(tets_line, "tetrahedron " + std::to_string(i + 1) + ": vertex index " +
                                 std::to_string(mesh.tets(i, k) + 1) + " out of range 1.." +
                                 std::to_string(mesh.vertices.rows()));
}

}  // namespace

TetMesh read_medit(const std::string& path) {
  const std::string data = read_whole_file(path);
  Scanner s(path, data);
  TetMesh mesh;
  bool have_vertices = false, have_tets = false, seen_version = false, ended = false;
  size_t tets_line = 0;
  FieldValues refs;
  std::string_view tok;
  while (!ended && s.next(tok)) {
    const std::string kw = lower(tok);
    if (kw == "meshversionformatted") {
      const long long v = s.need_int("the MeshVersionFormatted number");
      if (v < 1 || v > 4) s.fail("MeshVersionFormatted " + std::to_string(v) + " is not 1..4");
      seen_version = true;
    } else if (kw == "dimension") {
      const long long d = s.need_int("the dimension");
      if (d != 3) s.fail("Dimension is " + std::to_string(d) + ", only 3 is supported");
    } else if (kw == "end") {
      ended = true;
    } else if (kw == "vertices") {
      if (have_vertices) s.fail("second Vertices section");
      read_vertices(s, mesh);
      have_vertices = true;
    } else if (kw == "tetrahedra") {
      if (have_tets) s.fail("second Tetrahedra section");
      tets_line = s.line();
      read_tetrahedra(s, mesh, have_vertices, refs);
      have_tets = true;
    } else if (skipped_sections().count(kw)) {
      const int per = skipped_sections().at(kw);
      if (per != 0) skip_entries(s, tok, per);
    } else {
      s.fail("unknown keyword " + show(tok) + " (expected Vertices, Tetrahedra, End, ...)");
    }
  }
  if (!seen_version && !have_vertices) s.fail_at(1, "not a Medit .mesh file (no MeshVersionFormatted)");
  if (!have_vertices) s.fail("no Vertices section (truncated file?)");
  if (!have_tets) s.fail("no Tetrahedra section (truncated file?)");
  check_late_indices(s, mesh, tets_line);
  if (mesh.tets.rows() > 0 && (refs.array() != 0).any()) mesh.set_cell_field("label", std::move(refs), true);
  return mesh;
}

void write_medit(const std::string& path, const TetMesh& mesh) {
  const std::vector<int> labels = integer_labels(mesh);
  const Triangles faces = vpm::boundary_faces(mesh.tets);
  AtomicFile file(path);
  TextOut o(file.stream());
  o << "MeshVersionFormatted 2\n\nDimension 3\n\nVertices\n";
  o.integer(mesh.num_vertices()) << '\n';
  for (int i = 0; i < mesh.num_vertices(); ++i) {
    o.real(mesh.vertices(i, 0)) << ' ';
    o.real(mesh.vertices(i, 1)) << ' ';
    o.real(mesh.vertices(i, 2)) << " 0\n";
  }
  o << "\nTetrahedra\n";
  o.integer(mesh.num_tets()) << '\n';
  for (int i = 0; i < mesh.num_tets(); ++i) {
    for (int k = 0; k < 4; ++k) o.integer(mesh.tets(i, k) + 1) << ' ';
    o.integer(labels.empty() ? 0 : labels[static_cast<size_t>(i)]) << '\n';
  }
  o << "\nTriangles\n";
  o.integer(faces.rows()) << '\n';
  for (Eigen::Index i = 0; i < faces.rows(); ++i) {
    for (int k = 0; k < 3; ++k) o.integer(faces(i, k) + 1) << ' ';
    o << "0\n";
  }
  o << "\nEnd\n";
  o.flush();
  file.commit();
}

}  // namespace vpm::detail
