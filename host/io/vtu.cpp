// Reading VTK XML UnstructuredGrid (.vtu) and PolyData (.vtp): ASCII and the binary forms VTK and
// ParaView write (inline base64, appended raw or base64, zlib-compressed; io/vtk_binary.hpp).
// .vtu: points, tets (VTK type 10) and every point/cell field; non-tet cells are skipped (with
// their cell-data rows). .vtp: points, triangles (Polys of three points; vertices, lines and
// strips refused) and every point/cell field. The writers are in vtu_write.cpp and vtp.cpp.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>

#include "io/formats.hpp"
#include "io/text.hpp"
#include "io/vtk_binary.hpp"
#include "io/vtu_arrays.hpp"
#include "io/xml.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

// The state of one read: the tags seen so far and the arrays they hold.
class VtuReader {
 public:
  VtuReader(const std::string& path, const std::string& data, bool poly)
      : path_(path), data_(data), w_(path, data), poly_(poly), kind_(poly ? "PolyData" : "UnstructuredGrid"),
        cells_(poly ? "Polys" : "Cells") {}
  void read_tags();
  void check_complete();
  TetMesh build_mesh();
  TriSurface build_surface();

 private:
  void on_vtkfile(const Tag& tag);
  void on_piece(const Tag& tag);
  void on_data_array(const Tag& tag);
  void read_connectivity(const Tag& tag);
  void read_appended(const Tag& tag);
  std::vector<int> tet_cells() const;
  void set_fields(TetMesh& mesh, const std::vector<int>& keep) const;

  const std::string& path_;
  const std::string& data_;
  XmlWalker w_;
  const bool poly_;
  const std::string kind_, cells_;  // "UnstructuredGrid", "Cells" or "PolyData", "Polys"
  bool seen_file_ = false, seen_piece_ = false, closed_ = false;
  long long n_ = -1, m_ = -1;
  size_t piece_line_ = 1;
  std::string section_;  // PointData, CellData, Points, Cells
  std::vector<VtuArray> point_fields_, cell_fields_;
  VtuArray points_, conn_, offsets_, types_;
  bool have_points_ = false, have_conn_ = false, have_offsets_ = false, have_types_ = false;
  VtkBinaryLayout layout_;
  bool big_endian_ = false, compressed_ = false;
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
      read_appended(tag);
    } else if (tag.name == "Piece") {
      on_piece(tag);
    } else if (tag.name == "PointData" || tag.name == "CellData" || tag.name == "Points" ||
               tag.name == cells_) {
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
  if (it == tag.attrs.end() || it->second != kind_)
    w_.fail(tag.line, "not a VTK " + kind_ + " file (type=\"" + (it == tag.attrs.end() ? std::string() : it->second) + "\")");
  if (const auto c = tag.attrs.find("compressor"); c != tag.attrs.end() && !c->second.empty()) {
    if (c->second != "vtkZLibDataCompressor")
      w_.fail(tag.line, "compressor \"" + c->second + "\" is not supported (only vtkZLibDataCompressor)");
    layout_.zlib = compressed_ = true;
  }
  if (const auto h = tag.attrs.find("header_type"); h != tag.attrs.end()) {
    if (h->second != "UInt32" && h->second != "UInt64")
      w_.fail(tag.line, "header_type \"" + h->second + "\" (expected UInt32 or UInt64)");
    layout_.header_bytes = h->second == "UInt64" ? 8 : 4;
  }
  const auto order = tag.attrs.find("byte_order");
  layout_.big_endian = big_endian_ = order != tag.attrs.end() && order->second == "BigEndian";
}

// <AppendedData encoding="raw|base64">_DATA</AppendedData>: the blob of every appended array
// starts at its offset after the underscore (bytes for raw, characters for base64).
void VtuReader::read_appended(const Tag& tag) {
  const auto enc = tag.attrs.find("encoding");
  const std::string encoding = enc == tag.attrs.end() ? "raw" : enc->second;
  if (encoding != "raw" && encoding != "base64")
    w_.fail(tag.line, "AppendedData encoding=\"" + encoding + "\" (expected raw or base64)");
  if (big_endian_) w_.fail(tag.line, "big-endian binary data are not supported (byte_order=\"BigEndian\")");
  const std::string_view d = w_.data();
  const size_t start = d.find('_', tag.end);
  const size_t end = d.rfind("</AppendedData>");
  if (start == std::string_view::npos || end == std::string_view::npos || end < start)
    w_.fail(tag.line, "AppendedData without its '_' marker or its closing tag (truncated file?)");
  const std::string_view blob = d.substr(start + 1, end - start - 1);
  std::vector<VtuArray*> pending;
  for (VtuArray* a : {&points_, &conn_, &offsets_, &types_})
    if (a->appended_offset >= 0) pending.push_back(a);
  for (auto* list : {&point_fields_, &cell_fields_})
    for (VtuArray& a : *list)
      if (a.appended_offset >= 0) pending.push_back(&a);
  std::vector<long long> starts;
  for (const VtuArray* a : pending) starts.push_back(a->appended_offset);
  std::sort(starts.begin(), starts.end());
  for (VtuArray* a : pending) {
    const std::string shown = a->name.empty() ? std::string("(unnamed)") : a->name;
    const VtkBinaryFail fail = [&](const std::string& what) { w_.fail(a->line, "DataArray '" + shown + "': " + what); };
    const size_t off = static_cast<size_t>(a->appended_offset);
    if (off >= blob.size()) fail("offset " + std::to_string(off) + " is past the appended data (truncated file?)");
    std::vector<unsigned char> bytes;
    if (encoding == "raw") {
      size_t used = 0;
      bytes = vtk_raw_blob(reinterpret_cast<const unsigned char*>(blob.data()) + off, blob.size() - off, layout_, used, fail);
    } else {  // this array's characters run to the next array's offset
      const auto next = std::upper_bound(starts.begin(), starts.end(), a->appended_offset);
      const size_t stop = next == starts.end() ? blob.size() : static_cast<size_t>(*next);
      bytes = vtk_base64_blob(blob.substr(off, stop - off), layout_, fail);
    }
    set_binary_values(w_, *a, bytes);
    a->appended_offset = -1;
  }
  w_.set_pos(end);
}

void VtuReader::on_piece(const Tag& tag) {
  if (!seen_file_) w_.fail(tag.line, "<Piece> outside <VTKFile type=\"" + kind_ + "\">");
  if (seen_piece_) w_.fail(tag.line, "more than one <Piece>: only single-piece files are supported");
  seen_piece_ = true;
  piece_line_ = tag.line;
  n_ = attr_count(w_, tag, "NumberOfPoints", true, 0);
  m_ = attr_count(w_, tag, poly_ ? "NumberOfPolys" : "NumberOfCells", true, 0);
  if (poly_)
    for (const char* other : {"NumberOfVerts", "NumberOfLines", "NumberOfStrips"})
      if (attr_count(w_, tag, other, false, 0) != 0)
        w_.fail(tag.line, std::string(other) + " is not 0: only triangles (Polys) make a surface");
  // A point takes >= 3 values of >= 2 bytes, a cell >= 3 values (offset, type, index): 2x margin
  // (compressed data can be smaller).
  if (!compressed_ && n_ * 3 + m_ * 3 > static_cast<long long>(data_.size()))
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
    points_ = read_array(path_, w_, tag, n_, layout_, "Points");
    if (points_.comps != 3) w_.fail(tag.line, "Points must have 3 components, found " + std::to_string(points_.comps));
    have_points_ = true;
  } else if (section_ == "PointData") {
    point_fields_.push_back(read_array(path_, w_, tag, n_, layout_));
  } else if (section_ == "CellData") {
    cell_fields_.push_back(read_array(path_, w_, tag, m_, layout_));
  } else if (name == "offsets") {
    offsets_ = read_array(path_, w_, tag, m_, layout_);
    have_offsets_ = true;
  } else if (name == "types") {
    types_ = read_array(path_, w_, tag, m_, layout_);
    have_types_ = true;
  } else if (name == "connectivity") {
    read_connectivity(tag);
  }
}

// The connectivity's length is the last offset; VTK writes connectivity first, so without
// offsets yet (or with offsets whose values come later, in <AppendedData>) its tokens are counted.
void VtuReader::read_connectivity(const Tag& tag) {
  const auto fmt = tag.attrs.find("format");
  if (fmt != tag.attrs.end() && fmt->second != "ascii") {
    conn_ = read_array(path_, w_, tag, -1, layout_);  // its length is checked against the offsets later
  } else if (!have_offsets_ || offsets_.values.size() != static_cast<size_t>(std::max(m_, 0LL))) {
    const size_t close = array_close(w_, tag, "DataArray 'connectivity'");
    const AsciiPieces pieces = ascii_pieces(array_text(w_, tag, close));  // counted once, read with them
    conn_ = read_array(path_, w_, tag, pieces.total(), layout_, "(unnamed)", &pieces);
  } else {
    const double last = m_ > 0 ? offsets_.values.back() : 0.0;
    if (!(last >= 0 && last < 4.0e9))
      w_.fail(offsets_.line, "last offset in 'offsets' is negative or too large");
    const long long len = static_cast<long long>(last);
    conn_ = read_array(path_, w_, tag, len, layout_);
  }
  have_conn_ = true;
}

void VtuReader::check_complete() {
  if (!seen_file_) throw InputError(path_ + ":1: not a VTK XML file (no <VTKFile> element)");
  const size_t last = w_.line_at(data_.size());
  if (!seen_piece_) throw InputError(path_ + ":" + std::to_string(last) + ": no <Piece> element (truncated file?)");
  if (!closed_) throw InputError(path_ + ":" + std::to_string(last) + ": no </VTKFile> (truncated file?)");
  if (!have_points_) w_.fail(piece_line_, "Piece has no <Points> array");
  for (const VtuArray* a : {&points_, &conn_, &offsets_, &types_})
    if (a->appended_offset >= 0) w_.fail(a->line, "appended DataArray '" + a->name + "' but no <AppendedData> (truncated file?)");
  for (const auto* list : {&point_fields_, &cell_fields_})
    for (const VtuArray& a : *list)
      if (a.appended_offset >= 0) w_.fail(a.line, "appended DataArray '" + a.name + "' but no <AppendedData> (truncated file?)");
  for (const VtuArray* a : {&conn_, &offsets_, &types_})
    if (!a->type.empty() && !is_integer_type(a->type))
      w_.fail(a->line, cells_ + " array '" + a->name + "' has type " + a->type + ", expected an integer type");
  if (m_ > 0 && (!have_conn_ || !have_offsets_ || (!poly_ && !have_types_)))
    w_.fail(piece_line_, "Piece lacks a " + cells_ + " array (connectivity, offsets" + (poly_ ? ")" : ", types)"));
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

// Every poly a triangle with its points in range; the fields as read.
TriSurface VtuReader::build_surface() {
  TriSurface s;
  s.vertices.resize(n_, 3);
  std::copy(points_.values.begin(), points_.values.end(), s.vertices.data());
  s.triangles.resize(m_, 3);
  long long prev = 0;
  for (long long c = 0; c < m_; ++c) {
    const double off = offsets_.values[static_cast<size_t>(c)];
    if (!(off == static_cast<double>(prev + 3)) || off > static_cast<double>(conn_.values.size()))
      w_.fail(offsets_.line, "poly " + std::to_string(c) + ": offset " + std::to_string(static_cast<long long>(off)) +
                                 (off > static_cast<double>(conn_.values.size()) ? " is beyond the connectivity" : " does not close a triangle (3 points)"));
    for (int k = 0; k < 3; ++k) {
      const double v = conn_.values[static_cast<size_t>(prev + k)];
      if (!(v >= 0 && v < static_cast<double>(n_)))
        w_.fail(conn_.line, "poly " + std::to_string(c) + ": point index " + std::to_string(static_cast<long long>(v)) +
                                " out of range 0.." + std::to_string(n_ - 1));
      s.triangles(c, k) = static_cast<int>(v);
    }
    prev += 3;
  }
  for (const auto* list : {&point_fields_, &cell_fields_})
    for (const VtuArray& a : *list) {
      if (a.name.empty()) w_.fail(a.line, "DataArray without a Name");
      FieldValues v(list == &point_fields_ ? n_ : m_, a.comps);
      std::copy(a.values.begin(), a.values.end(), v.data());
      (list == &point_fields_ ? s.point_data : s.cell_data).push_back({a.name, std::move(v), is_integer_type(a.type)});
    }
  return s;
}

}  // namespace

TriSurface read_vtp(const std::string& path) {
  const std::string data = read_whole_file(path);
  VtuReader reader(path, data, true);
  reader.read_tags();
  reader.check_complete();
  return reader.build_surface();
}

TetMesh read_vtu(const std::string& path) {
  const std::string data = read_whole_file(path);
  VtuReader reader(path, data, false);
  reader.read_tags();
  reader.check_complete();
  return reader.build_mesh();
}

}  // namespace vpm::detail
