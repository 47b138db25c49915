// TetGen .node/.ele (+ .face on write). Format: https://wias-berlin.de/software/tetgen/fformats.html
// .node: "<#points> <dim=3> <#attributes> <#markers 0|1>", then "<i> <x> <y> <z> [attr...] [marker]".
// .ele:  "<#tets> <nodes per tet 4|10> <#region attributes 0|1>", then "<i> <n1..n4> [..n10] [region]".
// The first node's number (0 or 1) sets the numbering of every index, as in TetGen.
// '#' starts a comment. Node attributes and boundary markers are parsed and dropped; the
// region attribute becomes the cell field `label` (integer when all values are integral).
#include <cmath>
#include <filesystem>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"
#include "vpm/topology.hpp"

namespace vpm::detail {

namespace {

std::string stem_of(const std::string& path) {
  std::filesystem::path p(path);
  return (p.parent_path() / p.stem()).string();
}

std::string join_path(const std::string& stem, const char* ext) { return stem + ext; }

std::string n_of(int k, const char* what) { return std::to_string(k) + " " + what; }

// The header's count at position `k`, `fallback` where the header is shorter.
int header_count(const Scanner& s, const std::vector<std::string_view>& t, size_t k, const std::string& what,
                 int fallback) {
  return t.size() > k ? s.to_count(t[k], what) : fallback;
}

// Reads the .node file into mesh.vertices; returns the numbering base (0 or 1) of its first point.
int read_node_file(const std::string& node_path, TetMesh& mesh) {
  std::vector<std::string_view> t;
  int base = 0;
  const std::string data = read_whole_file(node_path);
  Scanner s(node_path, data);
  s.need_line(t, "the .node header '<#points> 3 <#attributes> <#markers>'");
  const int n = s.to_count(t[0], "the number of points");
  const int dim = header_count(s, t, 1, "the dimension", 3);
  const int nattr = header_count(s, t, 2, "the number of attributes", 0);
  const int nmark = header_count(s, t, 3, "the number of boundary markers", 0);
  if (dim != 3) s.fail("dimension is " + std::to_string(dim) + ", only 3 is supported");
  if (nmark > 1) s.fail("number of boundary markers must be 0 or 1, found " + std::to_string(nmark));
  if (nattr > 1000) s.fail("number of attributes " + std::to_string(nattr) + " is implausible");
  s.check_fits(n, 4, "points");
  const size_t need = 4 + static_cast<size_t>(nattr) + static_cast<size_t>(nmark);
  mesh.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) {
    s.need_line_lazy(t, [&] { return "point " + std::to_string(i + 1) + " of " + n_of(n, "declared"); });
    if (t.size() < need)
      s.fail("point line has " + std::to_string(t.size()) + " values, expected " +
             std::to_string(need) + " (number, x, y, z, " + n_of(nattr, "attributes") + ", " +
             n_of(nmark, "markers") + ")");
    const long long id = s.to_int(t[0], "the point number");
    if (i == 0) {
      if (id != 0 && id != 1)
        s.fail("first point number must be 0 or 1 (it sets the numbering), found " +
               std::to_string(id));
      base = static_cast<int>(id);
    } else if (id != base + i) {
      s.fail("point numbers must be consecutive: expected " + std::to_string(base + i) +
             ", found " + std::to_string(id));
    }
    for (int k = 0; k < 3; ++k) mesh.vertices(i, k) = s.to_real(t[1 + k], "a coordinate");
    for (size_t k = 4; k < need; ++k) s.to_real(t[k], "an attribute or marker");
  }
  if (!s.at_end())
    s.fail("unexpected data after the " + n_of(n, "points") + " the header declares");
  return base;
}

// Reads the .ele file (node indices numbered from `base`, as in `node_path`) into mesh.tets and
// the region attribute into the cell field `label`.
void read_ele_file(const std::string& ele_path, const std::string& node_path, int base, TetMesh& mesh) {
  std::vector<std::string_view> t;
  const std::string data = read_whole_file(ele_path);
  Scanner s(ele_path, data);
  s.need_line(t, "the .ele header '<#tets> <4|10> <#region attributes>'");
  const int m = s.to_count(t[0], "the number of tetrahedra");
  const int npt = header_count(s, t, 1, "nodes per tetrahedron", 4);
  const int nreg = header_count(s, t, 2, "the number of region attributes", 0);
  if (npt != 4 && npt != 10)
    s.fail("nodes per tetrahedron must be 4 or 10, found " + std::to_string(npt));
  if (nreg > 1) s.fail("number of region attributes must be 0 or 1, found " + std::to_string(nreg));
  s.check_fits(m, 5, "tetrahedra");
  const size_t need = 1 + static_cast<size_t>(npt) + static_cast<size_t>(nreg);
  const long long n = mesh.vertices.rows();
  mesh.tets.resize(m, 4);
  FieldValues region(nreg ? m : 0, 1);
  bool integral = true;
  for (int i = 0; i < m; ++i) {
    s.need_line_lazy(t, [&] { return "tetrahedron " + std::to_string(i + 1) + " of " + n_of(m, "declared"); });
    if (t.size() < need)
      s.fail("tetrahedron line has " + std::to_string(t.size()) + " values, expected " +
             std::to_string(need) + " (number, " + std::to_string(npt) + " nodes, " +
             n_of(nreg, "region attributes") + ")");
    for (int k = 0; k < 4; ++k) {
      const long long v = s.to_int(t[1 + k], "a node index");
      if (v < base || v - base >= n) {
        std::string why = "tetrahedron " + std::to_string(i + base) + ": node index " +
                          std::to_string(v) + " out of range " + std::to_string(base) + ".." +
                          std::to_string(n - 1 + base) + " (" + node_path + " numbers from " +
                          std::to_string(base) + ")";
        if (base == 1 && v == 0) why += ": the .ele looks 0-based but the .node is 1-based";
        if (base == 0 && v == n) why += ": the .ele looks 1-based but the .node is 0-based";
        s.fail(why);
      }
      mesh.tets(i, k) = static_cast<int>(v - base);
    }
    for (size_t k = 5; k < 1 + static_cast<size_t>(npt); ++k) s.to_int(t[k], "a node index");
    if (nreg) {
      const double r = s.to_real(t[1 + npt], "the region attribute");
      region(i, 0) = r;
      integral = integral && r == std::floor(r) && std::fabs(r) < 2147483647.0;
    }
  }
  if (!s.at_end())
    s.fail("unexpected data after the " + n_of(m, "tetrahedra") + " the header declares");
  if (nreg) mesh.set_cell_field("label", std::move(region), integral);
}

}  // namespace

TetMesh read_tetgen(const std::string& path) {
  const std::string stem = stem_of(path);
  const std::string node_path = join_path(stem, ".node"), ele_path = join_path(stem, ".ele");
  TetMesh mesh;
  const int base = read_node_file(node_path, mesh);
  read_ele_file(ele_path, node_path, base, mesh);
  return mesh;
}

void write_tetgen(const std::string& path, const TetMesh& mesh) {
  const std::string stem = stem_of(path);
  const Triangles faces = vpm::boundary_faces(mesh.tets);
  const std::vector<char> on_boundary =
      boundary_vertex_mask(mesh.num_vertices(), faces);
  const std::vector<int> labels = integer_labels(mesh);
  AtomicFile node(join_path(stem, ".node")), ele(join_path(stem, ".ele")),
      face(join_path(stem, ".face"));
  {
    TextOut o(node.stream());
    o << "# written by vpm: <#points> <dim> <#attributes> <#boundary markers>\n";
    o.integer(mesh.num_vertices()) << " 3 0 1\n";
    for (int i = 0; i < mesh.num_vertices(); ++i) {
      o.integer(i + 1) << ' ';
      o.real(mesh.vertices(i, 0)) << ' ';
      o.real(mesh.vertices(i, 1)) << ' ';
      o.real(mesh.vertices(i, 2)) << ' ';
      o.integer(on_boundary[static_cast<size_t>(i)] ? 1 : 0) << '\n';
    }
  }
  {
    TextOut o(ele.stream());
    o << "# written by vpm: <#tetrahedra> <nodes per tet> <#region attributes>\n";
    o.integer(mesh.num_tets()) << (labels.empty() ? " 4 0\n" : " 4 1\n");
    for (int i = 0; i < mesh.num_tets(); ++i) {
      o.integer(i + 1);
      for (int k = 0; k < 4; ++k) o << ' ', o.integer(mesh.tets(i, k) + 1);
      if (!labels.empty()) o << ' ', o.integer(labels[static_cast<size_t>(i)]);
      o << '\n';
    }
  }
  {
    TextOut o(face.stream());
    o << "# written by vpm: boundary triangles <#faces> <#boundary markers>\n";
    o.integer(faces.rows()) << " 1\n";
    for (Eigen::Index i = 0; i < faces.rows(); ++i) {
      o.integer(i + 1);
      for (int k = 0; k < 3; ++k) o << ' ', o.integer(faces(i, k) + 1);
      o << " 1\n";
    }
  }
  node.commit();
  ele.commit();
  face.commit();
}

}  // namespace vpm::detail
