// VTK XML UnstructuredGrid (.vtu), ASCII data only. Writes points, tets (VTK type 10) and every
// point/cell field (Int32 for integer fields, Float64 otherwise); reads them back. Non-tet cells
// are skipped on read (with their cell-data rows).
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "io/xml.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

struct Array {
  std::string name, type;
  int comps = 1;
  std::vector<double> values;
  size_t line = 1;
};

bool is_integer_type(const std::string& t) {
  return t.rfind("Int", 0) == 0 || t.rfind("UInt", 0) == 0;
}

long long attr_count(const XmlWalker& w, const Tag& tag, const std::string& key, bool required,
                     long long fallback) {
  auto it = tag.attrs.find(key);
  if (it == tag.attrs.end()) {
    if (required) w.fail(tag.line, "<" + tag.name + "> has no " + key + " attribute");
    return fallback;
  }
  const std::string& v = it->second;
  char* end = nullptr;
  errno = 0;
  const long long x = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno)
    w.fail(tag.line, key + "=\"" + v + "\" is not an integer (not a number)");
  if (x < 0) w.fail(tag.line, "negative count " + key + "=\"" + v + "\"");
  if (x > 2147483647LL) w.fail(tag.line, key + "=\"" + v + "\" is too large");
  return x;
}

// Position of the "</DataArray" closing `tag`; `label` names the array in the message if absent.
size_t array_close(const XmlWalker& w, const Tag& tag, const std::string& label) {
  const size_t close = w.data().find("</DataArray", tag.end);
  if (close == std::string_view::npos) w.fail(tag.line, label + " is not closed (truncated file?)");
  return close;
}

// Reads a DataArray's ASCII content: exactly `rows` tuples of its components.
Array read_array(const std::string& path, XmlWalker& w, const Tag& tag, long long rows,
                 const char* unnamed = "(unnamed)") {
  Array a;
  a.line = tag.line;
  a.name = tag.attrs.count("Name") ? tag.attrs.at("Name") : "";
  const std::string shown = a.name.empty() ? std::string(unnamed) : a.name;
  a.type = tag.attrs.count("type") ? tag.attrs.at("type") : "";
  if (a.type.empty()) w.fail(tag.line, "<DataArray Name=\"" + a.name + "\"> has no type attribute");
  a.comps = static_cast<int>(attr_count(w, tag, "NumberOfComponents", false, 1));
  if (a.comps < 1 || a.comps > 1000)
    w.fail(tag.line, "DataArray '" + shown + "': NumberOfComponents=" + std::to_string(a.comps) +
                         " is out of range");
  const std::string fmt = tag.attrs.count("format") ? tag.attrs.at("format") : "ascii";
  if (fmt != "ascii")
    w.fail(tag.line, "DataArray '" + shown + "' has format=\"" + fmt +
                         "\": only ASCII .vtu is supported (save as ASCII in ParaView)");
  if (tag.self_closing) {
    if (rows != 0) w.fail(tag.line, "DataArray '" + shown + "' is empty, expected " + std::to_string(rows) + " tuples");
    return a;
  }
  const size_t close = array_close(w, tag, "DataArray '" + shown + "'");
  Scanner s(path, w.data().substr(tag.end, close - tag.end), '\0', w.line_at(tag.end));
  const long long count = rows * a.comps;
  s.check_fits(count, 1, "values in DataArray '" + shown + "'");
  a.values.resize(static_cast<size_t>(count));
  const bool integer = is_integer_type(a.type);
  std::string_view tok;
  const std::string what = "DataArray '" + shown + "'";
  for (long long i = 0; i < count; ++i) {
    if (!s.next(tok))
      s.fail("DataArray '" + shown + "' has " + std::to_string(i) + " values, expected " +
             std::to_string(count) + " (wrong count or truncated)");
    a.values[static_cast<size_t>(i)] = integer ? static_cast<double>(s.to_int(tok, what)) : s.to_real(tok, what);
  }
  if (s.next(tok))
    s.fail("DataArray '" + shown + "' has more than the " + std::to_string(count) +
           " values expected (wrong count)");
  w.set_pos(close);
  return a;
}

// The state of one read: the tags seen so far and the arrays they hold.
class VtuReader {
 public:
  VtuReader(const std::string& path, const std::string& data) : path_(path), data_(data), w_(path, data) {}
  void read_tags();
  void check_complete();
  TetMesh build_mesh();

 private:
  void on_vtkfile(const Tag& tag);
  void on_piece(const Tag& tag);
  void on_data_array(const Tag& tag);
  void read_connectivity(const Tag& tag);
  std::vector<int> tet_cells() const;
  void set_fields(TetMesh& mesh, const std::vector<int>& keep) const;

  const std::string& path_;
  const std::string& data_;
  XmlWalker w_;
  bool seen_file_ = false, seen_piece_ = false, closed_ = false;
  long long n_ = -1, m_ = -1;
  size_t piece_line_ = 1;
  std::string section_;  // PointData, CellData, Points, Cells
  std::vector<Array> point_fields_, cell_fields_;
  Array points_, conn_, offsets_, types_;
  bool have_points_ = false, have_conn_ = false, have_offsets_ = false, have_types_ = false;
};

void VtuReader::read_tags() {
  Tag tag;
  while (w_.next(tag)) {
    if (tag.closing) {
      if (tag.name == section_) section_.clear();
      if (tag.name == "VTKFile") closed_ = true;
      continue;
    }
    if (tag.name == "VTKFile") {
      on_vtkfile(tag);
    } else if (tag.name == "AppendedData") {
      w_.fail(tag.line, "appended (binary) data is not supported: only ASCII .vtu");
    } else if (tag.name == "Piece") {
      on_piece(tag);
    } else if (tag.name == "PointData" || tag.name == "CellData" || tag.name == "Points" ||
               tag.name == "Cells") {
      if (!seen_piece_) w_.fail(tag.line, "<" + tag.name + "> outside <Piece>");
      if (!tag.self_closing) section_ = tag.name;
    } else if (tag.name == "DataArray") {
      on_data_array(tag);
    }
  }
}

void VtuReader::on_vtkfile(const Tag& tag) {
  seen_file_ = true;
  auto it = tag.attrs.find("type");
  if (it == tag.attrs.end() || it->second != "UnstructuredGrid")
    w_.fail(tag.line, "not a VTK UnstructuredGrid file (type=\"" +
                          (it == tag.attrs.end() ? std::string() : it->second) + "\")");
  if (tag.attrs.count("compressor"))
    w_.fail(tag.line, "compressed .vtu is not supported: only ASCII data");
}

void VtuReader::on_piece(const Tag& tag) {
  if (!seen_file_) w_.fail(tag.line, "<Piece> outside <VTKFile type=\"UnstructuredGrid\">");
  if (seen_piece_) w_.fail(tag.line, "more than one <Piece>: only single-piece .vtu is supported");
  seen_piece_ = true;
  piece_line_ = tag.line;
  n_ = attr_count(w_, tag, "NumberOfPoints", true, 0);
  m_ = attr_count(w_, tag, "NumberOfCells", true, 0);
  // A point takes >= 3 values of >= 2 bytes, a cell >= 3 values (offset, type, index): 2x margin.
  if (n_ * 3 + m_ * 3 > static_cast<long long>(data_.size()))
    w_.fail(tag.line, "declares " + std::to_string(n_) + " points and " + std::to_string(m_) +
                          " cells, more than the file's " + std::to_string(data_.size()) +
                          " bytes could hold (truncated or wrong count)");
}

void VtuReader::on_data_array(const Tag& tag) {
  if (section_.empty()) {
    if (!tag.self_closing) w_.set_pos(array_close(w_, tag, "DataArray"));  // e.g. FieldData: skip it
    return;
  }
  const std::string name = tag.attrs.count("Name") ? tag.attrs.at("Name") : "";
  if (section_ == "Points") {
    points_ = read_array(path_, w_, tag, n_, "Points");
    if (points_.comps != 3) w_.fail(tag.line, "Points must have 3 components, found " + std::to_string(points_.comps));
    have_points_ = true;
  } else if (section_ == "PointData") {
    point_fields_.push_back(read_array(path_, w_, tag, n_));
  } else if (section_ == "CellData") {
    cell_fields_.push_back(read_array(path_, w_, tag, m_));
  } else if (name == "offsets") {
    offsets_ = read_array(path_, w_, tag, m_);
    have_offsets_ = true;
  } else if (name == "types") {
    types_ = read_array(path_, w_, tag, m_);
    have_types_ = true;
  } else if (name == "connectivity") {
    read_connectivity(tag);
  }
}

// The connectivity's length is the last offset; VTK writes connectivity first, so without
// offsets yet its tokens are counted.
void VtuReader::read_connectivity(const Tag& tag) {
  if (!have_offsets_) {
    const size_t close = array_close(w_, tag, "DataArray 'connectivity'");
    Scanner c(path_, w_.data().substr(tag.end, close - tag.end), '\0');
    std::string_view tok;
    long long k = 0;
    while (c.next(tok)) ++k;
    conn_ = read_array(path_, w_, tag, k);
  } else {
    const double last = m_ > 0 ? offsets_.values.back() : 0.0;
    if (!(last >= 0 && last < 4.0e9))
      w_.fail(offsets_.line, "last offset in 'offsets' is negative or too large");
    const long long len = static_cast<long long>(last);
    conn_ = read_array(path_, w_, tag, len);
  }
  have_conn_ = true;
}

void VtuReader::check_complete() {
  if (!seen_file_) throw InputError(path_ + ":1: not a VTK XML file (no <VTKFile> element)");
  const size_t last = w_.line_at(data_.size());
  if (!seen_piece_) throw InputError(path_ + ":" + std::to_string(last) + ": no <Piece> element (truncated file?)");
  if (!closed_) throw InputError(path_ + ":" + std::to_string(last) + ": no </VTKFile> (truncated file?)");
  if (!have_points_) w_.fail(piece_line_, "Piece has no <Points> array");
  for (const Array* a : {&conn_, &offsets_, &types_})
    if (!a->type.empty() && !is_integer_type(a->type))
      w_.fail(a->line, "Cells array '" + a->name + "' has type " + a->type + ", expected an integer type");
  if (m_ > 0 && (!have_conn_ || !have_offsets_ || !have_types_))
    w_.fail(piece_line_, "Piece lacks a Cells array (connectivity, offsets, types)");
}

// The cells that are tetrahedra (VTK type 10), after checking every cell's offsets and the
// tetrahedra's point indices.
std::vector<int> VtuReader::tet_cells() const {
  std::vector<int> keep;
  long long prev = 0;
  for (long long c = 0; c < m_; ++c) {
    const double off = offsets_.values[static_cast<size_t>(c)];
    if (!(off >= prev) || off > static_cast<double>(conn_.values.size()))
      w_.fail(offsets_.line, "cell " + std::to_string(c) + ": offset " + std::to_string(static_cast<long long>(off)) +
                                 " is decreasing or beyond the " + std::to_string(conn_.values.size()) +
                                 " connectivity entries (wrong count)");
    const long long end = static_cast<long long>(off);
    const double type = types_.values[static_cast<size_t>(c)];
    if (type == 10) {
      if (end - prev != 4)
        w_.fail(offsets_.line, "cell " + std::to_string(c) + ": tetrahedron (type 10) with " +
                                   std::to_string(end - prev) + " points");
      for (long long k = prev; k < end; ++k) {
        const double v = conn_.values[static_cast<size_t>(k)];
        if (v < 0 || v >= static_cast<double>(n_))
          w_.fail(conn_.line, "cell " + std::to_string(c) + ": point index " +
                                  std::to_string(static_cast<long long>(v)) + " out of range 0.." +
                                  std::to_string(n_ - 1) + (v == n_ ? " (indices look 1-based; VTK is 0-based)" : ""));
      }
      keep.push_back(static_cast<int>(c));
    }
    prev = end;
  }
  if (m_ > 0 && keep.empty())
    w_.fail(piece_line_, "none of the " + std::to_string(m_) + " cells is a tetrahedron (VTK type 10)");
  return keep;
}

// Point fields as read, cell fields restricted to the kept cells.
void VtuReader::set_fields(TetMesh& mesh, const std::vector<int>& keep) const {
  for (auto& a : point_fields_) {
    if (a.name.empty()) w_.fail(a.line, "point DataArray without a Name");
    FieldValues v(n_, a.comps);
    std::copy(a.values.begin(), a.values.end(), v.data());
    mesh.set_point_field(a.name, std::move(v), is_integer_type(a.type));
  }
  for (auto& a : cell_fields_) {
    if (a.name.empty()) w_.fail(a.line, "cell DataArray without a Name");
    FieldValues v(static_cast<Eigen::Index>(keep.size()), a.comps);
    for (size_t t = 0; t < keep.size(); ++t)
      for (int k = 0; k < a.comps; ++k)
        v(static_cast<Eigen::Index>(t), k) = a.values[static_cast<size_t>(keep[t]) * a.comps + k];
    mesh.set_cell_field(a.name, std::move(v), is_integer_type(a.type));
  }
}

TetMesh VtuReader::build_mesh() {
  TetMesh mesh;
  mesh.vertices.resize(n_, 3);
  std::copy(points_.values.begin(), points_.values.end(), mesh.vertices.data());
  const std::vector<int> keep = tet_cells();
  mesh.tets.resize(static_cast<Eigen::Index>(keep.size()), 4);
  for (size_t t = 0; t < keep.size(); ++t) {
    const size_t start = keep[t] == 0 ? 0 : static_cast<size_t>(offsets_.values[static_cast<size_t>(keep[t] - 1)]);
    for (int k = 0; k < 4; ++k)
      mesh.tets(static_cast<Eigen::Index>(t), k) = static_cast<int>(conn_.values[start + static_cast<size_t>(k)]);
  }
  set_fields(mesh, keep);
  return mesh;
}

}  // namespace

TetMesh read_vtu(const std::string& path) {
  const std::string data = read_whole_file(path);
  VtuReader reader(path, data);
  reader.read_tags();
  reader.check_complete();
  return reader.build_mesh();
}

void write_vtu(const std::string& path, const TetMesh& mesh) {
  AtomicFile file(path);
  TextOut o(file.stream());
  const long long n = mesh.num_vertices(), m = mesh.num_tets();
  o << "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
       "  <UnstructuredGrid>\n"
       "    <Piece NumberOfPoints=\"";
  o.integer(n) << "\" NumberOfCells=\"";
  o.integer(m) << "\">\n";
  auto fields = [&](const char* section, const std::vector<Field>& fs) {
    o << "      <" << section << ">\n";
    for (const Field& f : fs) {
      o << "        <DataArray type=\"" << (f.integer ? "Int32" : "Float64") << "\" Name=\""
        << xml_escape(f.name) << "\" NumberOfComponents=\"";
      o.integer(f.values.cols()) << "\" format=\"ascii\">\n";
      for (Eigen::Index i = 0; i < f.values.rows(); ++i) {
        for (Eigen::Index k = 0; k < f.values.cols(); ++k) {
          if (k) o << ' ';
          if (f.integer)
            o.integer(static_cast<long long>(std::llround(f.values(i, k))));
          else
            o.real(f.values(i, k));
        }
        o << '\n';
      }
      o << "        </DataArray>\n";
    }
    o << "      </" << section << ">\n";
  };
  fields("PointData", mesh.point_data);
  fields("CellData", mesh.cell_data);
  o << "      <Points>\n"
       "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (long long i = 0; i < n; ++i) {
    o.real(mesh.vertices(i, 0)) << ' ';
    o.real(mesh.vertices(i, 1)) << ' ';
    o.real(mesh.vertices(i, 2)) << '\n';
  }
  o << "        </DataArray>\n"
       "      </Points>\n"
       "      <Cells>\n"
       "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (long long i = 0; i < m; ++i) {
    for (int k = 0; k < 4; ++k) {
      if (k) o << ' ';
      o.integer(mesh.tets(i, k));
    }
    o << '\n';
  }
  o << "        </DataArray>\n"
       "        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (long long i = 0; i < m; ++i) o.integer(4 * (i + 1)) << ((i % 16 == 15 || i + 1 == m) ? '\n' : ' ');
  o << "        </DataArray>\n"
       "        <DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (long long i = 0; i < m; ++i) o << ((i % 32 == 31 || i + 1 == m) ? "10\n" : "10 ");
  o << "        </DataArray>\n"
       "      </Cells>\n"
       "    </Piece>\n"
       "  </UnstructuredGrid>\n"
       "</VTKFile>\n";
  o.flush();
  file.commit();
}

}  // namespace vpm::detail
