// Gmsh .msh 4.1 ASCII. Reads $Nodes and the 4-node tetrahedra (element type 4) of $Elements;
// other element types are skipped. The physical tag of a tet's volume entity ($Entities)
// becomes the cell field `label` (0 where a volume has none; no field if no volume has one).
// Nodes are numbered in increasing tag order, tets in increasing element-tag order.
// Writes one volume entity per label value (physical tag = label, none for 0).
#include <algorithm>
#include <map>
#include <numeric>
#include <unordered_map>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {
std::string str(long long x) { return std::to_string(x); }
}  // namespace

TetMesh read_gmsh(const std::string& path) {
  const std::string data = read_whole_file(path);
  Scanner s(path, data, '\0');
  std::vector<std::string_view> t;
  bool have_format = false, have_nodes = false, have_elements = false;
  std::unordered_map<long long, int> volume_physical;  // volume entity tag -> physical tag
  std::vector<long long> node_tags;
  std::vector<double> xyz;
  struct Tet { long long tag; long long v[4]; int label; size_t line; };
  std::vector<Tet> tets;
  auto end_section = [&](const std::string& name) {
    s.need_line(t, "$End" + name);
    if (t[0] != "$End" + name) s.fail("expected $End" + name + ", found " + show(t[0]) + " (wrong count?)");
  };
  while (s.next_line(t)) {
    const std::string_view head = t[0];
    if (head.empty() || head[0] != '$') s.fail("expected a section like $Nodes, found " + show(head));
    if (head == "$MeshFormat") {
      s.need_line(t, "'4.1 0 8' (version, file type, data size)");
      if (t[0] != "4.1") s.fail("MSH version " + show(t[0]) + " is not supported: only 4.1 ASCII");
      if (t.size() < 2 || t[1] != "0") s.fail("binary .msh is not supported: only ASCII (file type 0)");
      end_section("MeshFormat");
      have_format = true;
    } else if (!have_format) {
      s.fail("not a Gmsh file: expected $MeshFormat first, found " + show(head));
    } else if (head == "$Entities") {
      s.need_line(t, "entity counts");
      if (t.size() < 4) s.fail("$Entities needs 4 counts (points, curves, surfaces, volumes)");
      long long counts[4];
      for (int k = 0; k < 4; ++k) counts[k] = s.to_count(t[static_cast<size_t>(k)], "an entity count");
      s.check_fits(counts[0] + counts[1] + counts[2] + counts[3], 4, "entities");
      for (int k = 0; k < 3; ++k)
        for (long long i = 0; i < counts[k]; ++i) s.need_line(t, "an entity line");
      for (long long i = 0; i < counts[3]; ++i) {
        s.need_line(t, "volume entity " + str(i + 1) + " of " + str(counts[3]));
        if (t.size() < 9) s.fail("volume entity line has " + str(static_cast<long long>(t.size())) + " values, expected at least 9");
        const long long tag = s.to_int(t[0], "the volume tag");
        const int nphys = s.to_count(t[7], "the number of physical tags");
        if (t.size() < 9 + static_cast<size_t>(nphys)) s.fail("volume entity line has fewer physical tags than it declares");
        if (nphys > 0) volume_physical[tag] = static_cast<int>(s.to_int(t[8], "a physical tag"));
      }
      end_section("Entities");
    } else if (head == "$Nodes") {
      if (have_nodes) s.fail("second $Nodes section");
      s.need_line(t, "'numEntityBlocks numNodes minNodeTag maxNodeTag'");
      if (t.size() < 4) s.fail("$Nodes header needs 4 numbers (blocks, nodes, min tag, max tag)");
      const int blocks = s.to_count(t[0], "the number of node blocks");
      const int n = s.to_count(t[1], "the number of nodes");
      s.check_fits(n, 4, "nodes");
      s.check_fits(blocks, 4, "node blocks");
      node_tags.reserve(static_cast<size_t>(n));
      xyz.reserve(static_cast<size_t>(n) * 3);
      for (int b = 0; b < blocks; ++b) {
        s.need_line(t, "node block " + str(b + 1) + " of " + str(blocks));
        if (t.size() < 4) s.fail("node block header needs 4 numbers (dim, tag, parametric, count)");
        const long long dim = s.to_int(t[0], "the entity dimension");
        const long long param = s.to_int(t[2], "the parametric flag");
        const int k = s.to_count(t[3], "the number of nodes in the block");
        if (static_cast<long long>(node_tags.size()) + k > n)
          s.fail("node blocks hold more than the " + str(n) + " nodes the header declares (wrong count)");
        const size_t ncoord = 3 + (param ? static_cast<size_t>(std::max(0LL, std::min(dim, 3LL))) : 0);
        for (int i = 0; i < k; ++i) {
          s.need_line_lazy(t, [&] { return "a node tag (" + str(i + 1) + " of " + str(k) + " in the block)"; });
          node_tags.push_back(s.to_int(t[0], "a node tag"));
        }
        for (int i = 0; i < k; ++i) {
          s.need_line_lazy(t, [&] { return "node coordinates (" + str(i + 1) + " of " + str(k) + " in the block)"; });
          if (t.size() < ncoord) s.fail("node has " + str(static_cast<long long>(t.size())) + " coordinates, expected " + str(static_cast<long long>(ncoord)));
          for (int c = 0; c < 3; ++c) xyz.push_back(s.to_real(t[static_cast<size_t>(c)], "a node coordinate"));
        }
      }
      if (static_cast<long long>(node_tags.size()) != n)
        s.fail("node blocks hold " + str(static_cast<long long>(node_tags.size())) + " nodes, the header declares " + str(n) + " (wrong count)");
      end_section("Nodes");
      have_nodes = true;
    } else if (head == "$Elements") {
      if (have_elements) s.fail("second $Elements section");
      s.need_line(t, "'numEntityBlocks numElements minTag maxTag'");
      if (t.size() < 4) s.fail("$Elements header needs 4 numbers (blocks, elements, min tag, max tag)");
      const int blocks = s.to_count(t[0], "the number of element blocks");
      const int m = s.to_count(t[1], "the number of elements");
      s.check_fits(m, 2, "elements");
      s.check_fits(blocks, 4, "element blocks");
      long long total = 0;
      for (int b = 0; b < blocks; ++b) {
        s.need_line(t, "element block " + str(b + 1) + " of " + str(blocks));
        if (t.size() < 4) s.fail("element block header needs 4 numbers (dim, tag, type, count)");
        const long long etag = s.to_int(t[1], "the entity tag");
        const long long type = s.to_int(t[2], "the element type");
        const int k = s.to_count(t[3], "the number of elements in the block");
        total += k;
        if (total > m) s.fail("element blocks hold more than the " + str(m) + " elements the header declares (wrong count)");
        const auto ph = volume_physical.find(etag);
        const int label = ph == volume_physical.end() ? 0 : ph->second;
        for (int i = 0; i < k; ++i) {
          s.need_line_lazy(t, [&] { return "element " + str(i + 1) + " of " + str(k) + " in the block"; });
          if (type != 4) continue;
          if (t.size() < 5) s.fail("tetrahedron line has " + str(static_cast<long long>(t.size())) + " values, expected 5 (tag and 4 nodes)");
          Tet tet{s.to_int(t[0], "an element tag"), {}, label, s.line()};
          for (int c = 0; c < 4; ++c) tet.v[c] = s.to_int(t[1 + static_cast<size_t>(c)], "a node tag");
          tets.push_back(tet);
        }
      }
      if (total != m) s.fail("element blocks hold " + str(total) + " elements, the header declares " + str(m) + " (wrong count)");
      end_section("Elements");
      have_elements = true;
    } else {
      // Skip an unknown section ($PhysicalNames, $NodeData, ...) up to its $End line.
      const std::string end = "$End" + std::string(head.substr(1));
      const size_t line = s.line();
      while (true) {
        if (!s.next_line(t)) s.fail_at(line, std::string(head) + " has no " + end + " (truncated file?)");
        if (t[0] == end) break;
      }
    }
  }
  if (!have_format) s.fail_at(1, "not a Gmsh file (no $MeshFormat)");
  if (!have_nodes) s.fail("no $Nodes section (truncated file?)");
  if (!have_elements) s.fail("no $Elements section (truncated file?)");

  // Nodes in increasing tag order.
  const size_t n = node_tags.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  if (!std::is_sorted(node_tags.begin(), node_tags.end()))
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return node_tags[a] < node_tags[b]; });
  TetMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(n), 3);
  std::vector<long long> sorted(n);
  for (size_t i = 0; i < n; ++i) {
    sorted[i] = node_tags[order[i]];
    for (int c = 0; c < 3; ++c) mesh.vertices(static_cast<Eigen::Index>(i), c) = xyz[order[i] * 3 + static_cast<size_t>(c)];
    if (i > 0 && sorted[i] == sorted[i - 1]) s.fail("node tag " + str(sorted[i]) + " appears twice");
  }
  const long long first = n ? sorted[0] : 0;
  const bool consecutive = n == 0 || sorted[n - 1] - first == static_cast<long long>(n) - 1;
  std::stable_sort(tets.begin(), tets.end(), [](const Tet& a, const Tet& b) { return a.tag < b.tag; });
  mesh.tets.resize(static_cast<Eigen::Index>(tets.size()), 4);
  bool any_label = false;
  FieldValues labels(static_cast<Eigen::Index>(tets.size()), 1);
  for (size_t i = 0; i < tets.size(); ++i) {
    for (int c = 0; c < 4; ++c) {
      const long long v = tets[i].v[c];
      auto it = consecutive ? (v >= first && v - first < static_cast<long long>(n) ? sorted.begin() + (v - first) : sorted.end())
                            : std::lower_bound(sorted.begin(), sorted.end(), v);
      if (it == sorted.end() || *it != v)
        s.fail_at(tets[i].line, "tetrahedron " + str(tets[i].tag) + ": node tag " + str(v) +
                                    " is not in $Nodes" + (v == 0 ? " (Gmsh tags start at 1; the file looks 0-based)" : ""));
      mesh.tets(static_cast<Eigen::Index>(i), c) = static_cast<int>(it - sorted.begin());
    }
    labels(static_cast<Eigen::Index>(i), 0) = tets[i].label;
    any_label = any_label || tets[i].label != 0;
  }
  if (any_label) mesh.set_cell_field("label", std::move(labels), true);
  return mesh;
}

void write_gmsh(const std::string& path, const TetMesh& mesh) {
  const std::vector<int> labels = integer_labels(mesh);
  // One volume entity per distinct label (one entity without physical tag if no labels).
  std::vector<int> values = labels;
  std::sort(values.begin(), values.end());
  values.erase(std::unique(values.begin(), values.end()), values.end());
  if (values.empty()) values.push_back(0);
  std::map<int, int> entity_of;
  for (size_t i = 0; i < values.size(); ++i) entity_of[values[i]] = static_cast<int>(i) + 1;
  std::vector<std::vector<int>> members(values.size());
  for (int i = 0; i < mesh.num_tets(); ++i)
    members[static_cast<size_t>(entity_of[labels.empty() ? 0 : labels[static_cast<size_t>(i)]] - 1)].push_back(i);

  AtomicFile file(path);
  TextOut o(file.stream());
  o << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n0 0 0 ";
  o.integer(static_cast<long long>(values.size())) << '\n';
  Eigen::RowVector3d lo = Eigen::RowVector3d::Zero(), hi = Eigen::RowVector3d::Zero();
  if (mesh.num_vertices() > 0) lo = mesh.vertices.colwise().minCoeff(), hi = mesh.vertices.colwise().maxCoeff();
  for (size_t i = 0; i < values.size(); ++i) {
    o.integer(static_cast<long long>(i) + 1);
    for (int c = 0; c < 3; ++c) o << ' ', o.real(lo(c));
    for (int c = 0; c < 3; ++c) o << ' ', o.real(hi(c));
    if (values[i] != 0) o << " 1 ", o.integer(values[i]);
    else o << " 0";
    o << " 0\n";
  }
  o << "$EndEntities\n$Nodes\n1 ";
  const long long n = mesh.num_vertices();
  o.integer(n) << (n ? " 1 " : " 0 ");
  o.integer(n) << "\n3 1 0 ";
  o.integer(n) << '\n';
  for (long long i = 0; i < n; ++i) o.integer(i + 1) << '\n';
  for (long long i = 0; i < n; ++i) {
    o.real(mesh.vertices(i, 0)) << ' ';
    o.real(mesh.vertices(i, 1)) << ' ';
    o.real(mesh.vertices(i, 2)) << '\n';
  }
  o << "$EndNodes\n$Elements\n";
  const long long m = mesh.num_tets();
  o.integer(static_cast<long long>(values.size())) << ' ';
  o.integer(m) << (m ? " 1 " : " 0 ");
  o.integer(m) << '\n';
  for (size_t e = 0; e < values.size(); ++e) {
    o << "3 ";
    o.integer(static_cast<long long>(e) + 1) << " 4 ";
    o.integer(static_cast<long long>(members[e].size())) << '\n';
    for (int i : members[e]) {
      o.integer(i + 1);
      for (int c = 0; c < 4; ++c) o << ' ', o.integer(mesh.tets(i, c) + 1);
      o << '\n';
    }
  }
  o << "$EndElements\n";
  o.flush();
  file.commit();
}

}  // namespace vpm::detail
