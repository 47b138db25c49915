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

struct Tet { long long tag; long long v[4]; int label; size_t line; };

// Counts of a $Nodes or $Elements header.
struct SectionHeader { int blocks; int count; };

// The state of one read: the sections seen so far and what they hold, in file order.
class GmshReader {
 public:
  GmshReader(const std::string& path, std::string_view data) : s_(path, data, '\0') {}
  void read_sections();
  TetMesh build_mesh();

 private:
  void end_section(const std::string& name);
  void read_format();
  void read_entities();
  SectionHeader read_section_header(bool seen, const std::string& section, const std::string& noun,
                                    const std::string& layout, long long min_bytes);
  void read_nodes();
  void read_elements();
  void skip_section(std::string_view head);

  Scanner s_;
  std::vector<std::string_view> t_;
  bool have_format_ = false, have_nodes_ = false, have_elements_ = false;
  std::unordered_map<long long, int> volume_physical_;  // volume entity tag -> physical tag
  std::vector<long long> node_tags_;
  std::vector<double> xyz_;
  std::vector<Tet> tets_;
};

void GmshReader::end_section(const std::string& name) {
  s_.need_line(t_, "$End" + name);
  if (t_[0] != "$End" + name) s_.fail("expected $End" + name + ", found " + show(t_[0]) + " (wrong count?)");
}

void GmshReader::read_sections() {
  while (s_.next_line(t_)) {
    const std::string_view head = t_[0];
    if (head.empty() || head[0] != '$') s_.fail("expected a section like $Nodes, found " + show(head));
    if (head == "$MeshFormat") read_format();
    else if (!have_format_) s_.fail("not a Gmsh file: expected $MeshFormat first, found " + show(head));
    else if (head == "$Entities") read_entities();
    else if (head == "$Nodes") read_nodes();
    else if (head == "$Elements") read_elements();
    else skip_section(head);
  }
  if (!have_format_) s_.fail_at(1, "not a Gmsh file (no $MeshFormat)");
  if (!have_nodes_) s_.fail("no $Nodes section (truncated file?)");
  if (!have_elements_) s_.fail("no $Elements section (truncated file?)");
}

void GmshReader::read_format() {
  s_.need_line(t_, "'4.1 0 8' (version, file type, data size)");
  if (t_[0] != "4.1") s_.fail("MSH version " + show(t_[0]) + " is not supported: only 4.1 ASCII");
  if (t_.size() < 2 || t_[1] != "0") s_.fail("binary .msh is not supported: only ASCII (file type 0)");
  end_section("MeshFormat");
  have_format_ = true;
}

// Keeps the first physical tag of each volume entity; points, curves and surfaces are skipped.
void GmshReader::read_entities() {
  s_.need_line(t_, "entity counts");
  if (t_.size() < 4) s_.fail("$Entities needs 4 counts (points, curves, surfaces, volumes)");
  long long counts[4];
  for (int k = 0; k < 4; ++k) counts[k] = s_.to_count(t_[static_cast<size_t>(k)], "an entity count");
  s_.check_fits(counts[0] + counts[1] + counts[2] + counts[3], 4, "entities");
  for (int k = 0; k < 3; ++k)
    for (long long i = 0; i < counts[k]; ++i) s_.need_line(t_, "an entity line");
  for (long long i = 0; i < counts[3]; ++i) {
    s_.need_line(t_, "volume entity " + str(i + 1) + " of " + str(counts[3]));
    if (t_.size() < 9) s_.fail("volume entity line has " + str(static_cast<long long>(t_.size())) + " values, expected at least 9");
    const long long tag = s_.to_int(t_[0], "the volume tag");
    const int nphys = s_.to_count(t_[7], "the number of physical tags");
    if (t_.size() < 9 + static_cast<size_t>(nphys)) s_.fail("volume entity line has fewer physical tags than it declares");
    if (nphys > 0) volume_physical_[tag] = static_cast<int>(s_.to_int(t_[8], "a physical tag"));
  }
  end_section("Entities");
}

// The header line of $Nodes or $Elements ("blocks count minTag maxTag"); `noun` is "node" or
// "element", `layout` the expected line, `min_bytes` the least bytes one item takes.
SectionHeader GmshReader::read_section_header(bool seen, const std::string& section, const std::string& noun,
                                              const std::string& layout, long long min_bytes) {
  if (seen) s_.fail("second $" + section + " section");
  s_.need_line(t_, layout);
  if (t_.size() < 4) s_.fail("$" + section + " header needs 4 numbers (blocks, " + noun + "s, min tag, max tag)");
  SectionHeader h{};
  h.blocks = s_.to_count(t_[0], "the number of " + noun + " blocks");
  h.count = s_.to_count(t_[1], "the number of " + noun + "s");
  s_.check_fits(h.count, min_bytes, noun + "s");
  s_.check_fits(h.blocks, 4, noun + " blocks");
  return h;
}

// Each node block lists its tags, then their coordinates (plus parametric ones, dropped).
void GmshReader::read_nodes() {
  const SectionHeader h = read_section_header(have_nodes_, "Nodes", "node", "'numEntityBlocks numNodes minNodeTag maxNodeTag'", 4);
  const int blocks = h.blocks, n = h.count;
  node_tags_.reserve(static_cast<size_t>(n));
  xyz_.reserve(static_cast<size_t>(n) * 3);
  for (int b = 0; b < blocks; ++b) {
    s_.need_line(t_, "node block " + str(b + 1) + " of " + str(blocks));
    if (t_.size() < 4) s_.fail("node block header needs 4 numbers (dim, tag, parametric, count)");
    const long long dim = s_.to_int(t_[0], "the entity dimension");
    const long long param = s_.to_int(t_[2], "the parametric flag");
    const int k = s_.to_count(t_[3], "the number of nodes in the block");
    if (static_cast<long long>(node_tags_.size()) + k > n)
      s_.fail("node blocks hold more than the " + str(n) + " nodes the header declares (wrong count)");
    const size_t ncoord = 3 + (param ? static_cast<size_t>(std::max(0LL, std::min(dim, 3LL))) : 0);
    for (int i = 0; i < k; ++i) {
      s_.need_line_lazy(t_, [&] { return "a node tag (" + str(i + 1) + " of " + str(k) + " in the block)"; });
      node_tags_.push_back(s_.to_int(t_[0], "a node tag"));
    }
    for (int i = 0; i < k; ++i) {
      s_.need_line_lazy(t_, [&] { return "node coordinates (" + str(i + 1) + " of " + str(k) + " in the block)"; });
      if (t_.size() < ncoord) s_.fail("node has " + str(static_cast<long long>(t_.size())) + " coordinates, expected " + str(static_cast<long long>(ncoord)));
      for (int c = 0; c < 3; ++c) xyz_.push_back(s_.to_real(t_[static_cast<size_t>(c)], "a node coordinate"));
    }
  }
  if (static_cast<long long>(node_tags_.size()) != n)
    s_.fail("node blocks hold " + str(static_cast<long long>(node_tags_.size())) + " nodes, the header declares " + str(n) + " (wrong count)");
  end_section("Nodes");
  have_nodes_ = true;
}

// Keeps the tetrahedra (type 4) with the physical tag of their volume entity; skips the rest.
void GmshReader::read_elements() {
  const SectionHeader h = read_section_header(have_elements_, "Elements", "element", "'numEntityBlocks numElements minTag maxTag'", 2);
  const int blocks = h.blocks, m = h.count;
  long long total = 0;
  for (int b = 0; b < blocks; ++b) {
    s_.need_line(t_, "element block " + str(b + 1) + " of " + str(blocks));
    if (t_.size() < 4) s_.fail("element block header needs 4 numbers (dim, tag, type, count)");
    const long long etag = s_.to_int(t_[1], "the entity tag");
    const long long type = s_.to_int(t_[2], "the element type");
    const int k = s_.to_count(t_[3], "the number of elements in the block");
    total += k;
    if (total > m) s_.fail("element blocks hold more than the " + str(m) + " elements the header declares (wrong count)");
    const auto ph = volume_physical_.find(etag);
    const int label = ph == volume_physical_.end() ? 0 : ph->second;
    for (int i = 0; i < k; ++i) {
      s_.need_line_lazy(t_, [&] { return "element " + str(i + 1) + " of " + str(k) + " in the block"; });
      if (type != 4) continue;
      if (t_.size() < 5) s_.fail("tetrahedron line has " + str(static_cast<long long>(t_.size())) + " values, expected 5 (tag and 4 nodes)");
      Tet tet{s_.to_int(t_[0], "an element tag"), {}, label, s_.line()};
      for (int c = 0; c < 4; ++c) tet.v[c] = s_.to_int(t_[1 + static_cast<size_t>(c)], "a node tag");
      tets_.push_back(tet);
    }
  }
  if (total != m) s_.fail("element blocks hold " + str(total) + " elements, the header declares " + str(m) + " (wrong count)");
  end_section("Elements");
  have_elements_ = true;
}

// Skips an unknown section ($PhysicalNames, $NodeData, ...) up to its $End line.
void GmshReader::skip_section(std::string_view head) {
  const std::string end = "$End" + std::string(head.substr(1));
  const size_t line = s_.line();
  while (true) {
    if (!s_.next_line(t_)) s_.fail_at(line, std::string(head) + " has no " + end + " (truncated file?)");
    if (t_[0] == end) break;
  }
}

// Nodes in increasing tag order, tets in increasing element-tag order with node tags turned
// into indices, and the `label` field where any volume has a physical tag.
TetMesh GmshReader::build_mesh() {
  const size_t n = node_tags_.size();
  std::vector<size_t> order(n);
  std::iota(order.begin(), order.end(), size_t{0});
  if (!std::is_sorted(node_tags_.begin(), node_tags_.end()))
    std::stable_sort(order.begin(), order.end(), [&](size_t a, size_t b) { return node_tags_[a] < node_tags_[b]; });
  TetMesh mesh;
  mesh.vertices.resize(static_cast<Eigen::Index>(n), 3);
  std::vector<long long> sorted(n);
  for (size_t i = 0; i < n; ++i) {
    sorted[i] = node_tags_[order[i]];
    for (int c = 0; c < 3; ++c) mesh.vertices(static_cast<Eigen::Index>(i), c) = xyz_[order[i] * 3 + static_cast<size_t>(c)];
    if (i > 0 && sorted[i] == sorted[i - 1]) s_.fail("node tag " + str(sorted[i]) + " appears twice");
  }
  const long long first = n ? sorted[0] : 0;
  const bool consecutive = n == 0 || sorted[n - 1] - first == static_cast<long long>(n) - 1;
  std::stable_sort(tets_.begin(), tets_.end(), [](const Tet& a, const Tet& b) { return a.tag < b.tag; });
  mesh.tets.resize(static_cast<Eigen::Index>(tets_.size()), 4);
  bool any_label = false;
  FieldValues labels(static_cast<Eigen::Index>(tets_.size()), 1);
  for (size_t i = 0; i < tets_.size(); ++i) {
    for (int c = 0; c < 4; ++c) {
      const long long v = tets_[i].v[c];
      auto it = consecutive ? (v >= first && v - first < static_cast<long long>(n) ? sorted.begin() + (v - first) : sorted.end())
                            : std::lower_bound(sorted.begin(), sorted.end(), v);
      if (it == sorted.end() || *it != v)
        s_.fail_at(tets_[i].line, "tetrahedron " + str(tets_[i].tag) + ": node tag " + str(v) +
                                      " is not in $Nodes" + (v == 0 ? " (Gmsh tags start at 1; the file looks 0-based)" : ""));
      mesh.tets(static_cast<Eigen::Index>(i), c) = static_cast<int>(it - sorted.begin());
    }
    labels(static_cast<Eigen::Index>(i), 0) = tets_[i].label;
    any_label = any_label || tets_[i].label != 0;
  }
  if (any_label) mesh.set_cell_field("label", std::move(labels), true);
  return mesh;
}

}  // namespace

TetMesh read_gmsh(const std::string& path) {
  const std::string data = read_whole_file(path);
  GmshReader reader(path, data);
  reader.read_sections();
  return reader.build_mesh();
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
