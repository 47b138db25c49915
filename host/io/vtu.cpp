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
  const std::string_view d = w.data();
  const size_t close = d.find("</DataArray", tag.end);
  if (close == std::string_view::npos)
    w.fail(tag.line, "DataArray '" + shown + "' is not closed (truncated file?)");
  Scanner s(path, d.substr(tag.end, close - tag.end), '\0', w.line_at(tag.end));
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

}  // namespace

TetMesh read_vtu(const std::string& path) {
  const std::string data = read_whole_file(path);
  XmlWalker w(path, data);
  Tag tag;
  bool seen_file = false, seen_piece = false;
  long long n = -1, m = -1;
  size_t piece_line = 1;
  std::string section;  // PointData, CellData, Points, Cells
  std::vector<Array> point_fields, cell_fields;
  Array points, conn, offsets, types;
  bool have_points = false, have_conn = false, have_offsets = false, have_types = false;
  bool closed = false;
  while (w.next(tag)) {
    if (tag.closing) {
      if (tag.name == section) section.clear();
      if (tag.name == "VTKFile") closed = true;
      continue;
    }
    if (tag.name == "VTKFile") {
      seen_file = true;
      auto it = tag.attrs.find("type");
      if (it == tag.attrs.end() || it->second != "UnstructuredGrid")
        w.fail(tag.line, "not a VTK UnstructuredGrid file (type=\"" +
                             (it == tag.attrs.end() ? std::string() : it->second) + "\")");
      if (tag.attrs.count("compressor"))
        w.fail(tag.line, "compressed .vtu is not supported: only ASCII data");
    } else if (tag.name == "AppendedData") {
      w.fail(tag.line, "appended (binary) data is not supported: only ASCII .vtu");
    } else if (tag.name == "Piece") {
      if (!seen_file) w.fail(tag.line, "<Piece> outside <VTKFile type=\"UnstructuredGrid\">");
      if (seen_piece) w.fail(tag.line, "more than one <Piece>: only single-piece .vtu is supported");
      seen_piece = true;
      piece_line = tag.line;
      n = attr_count(w, tag, "NumberOfPoints", true, 0);
      m = attr_count(w, tag, "NumberOfCells", true, 0);
      // A point takes >= 3 values of >= 2 bytes, a cell >= 3 values (offset, type, index): 2x margin.
      if (n * 3 + m * 3 > static_cast<long long>(data.size()))
        w.fail(tag.line, "declares " + std::to_string(n) + " points and " + std::to_string(m) +
                             " cells, more than the file's " + std::to_string(data.size()) +
                             " bytes could hold (truncated or wrong count)");
    } else if (tag.name == "PointData" || tag.name == "CellData" || tag.name == "Points" ||
               tag.name == "Cells") {
      if (!seen_piece) w.fail(tag.line, "<" + tag.name + "> outside <Piece>");
      if (!tag.self_closing) section = tag.name;
    } else if (tag.name == "DataArray") {
      if (section.empty()) {
        if (!tag.self_closing) {  // e.g. FieldData: skip its content
          const size_t close = w.data().find("</DataArray", tag.end);
          if (close == std::string_view::npos) w.fail(tag.line, "DataArray is not closed (truncated file?)");
          w.set_pos(close);
        }
        continue;
      }
      const std::string name = tag.attrs.count("Name") ? tag.attrs.at("Name") : "";
      if (section == "Points") {
        points = read_array(path, w, tag, n, "Points");
        if (points.comps != 3) w.fail(tag.line, "Points must have 3 components, found " + std::to_string(points.comps));
        have_points = true;
      } else if (section == "PointData") {
        point_fields.push_back(read_array(path, w, tag, n));
      } else if (section == "CellData") {
        cell_fields.push_back(read_array(path, w, tag, m));
      } else if (name == "offsets") {
        offsets = read_array(path, w, tag, m);
        have_offsets = true;
      } else if (name == "types") {
        types = read_array(path, w, tag, m);
        have_types = true;
      } else if (name == "connectivity") {
        if (!have_offsets) {
          // Length is known only from offsets; VTK writes connectivity first, so count tokens.
          const size_t close = w.data().find("</DataArray", tag.end);
          if (close == std::string_view::npos) w.fail(tag.line, "DataArray 'connectivity' is not closed (truncated file?)");
          Scanner c(path, w.data().substr(tag.end, close - tag.end), '\0');
          std::string_view tok;
          long long k = 0;
          while (c.next(tok)) ++k;
          conn = read_array(path, w, tag, k);
        } else {
          const double last = m > 0 ? offsets.values.back() : 0.0;
          if (!(last >= 0 && last < 4.0e9))
            w.fail(offsets.line, "last offset in 'offsets' is negative or too large");
          const long long len = static_cast<long long>(last);
          conn = read_array(path, w, tag, len);
        }
        have_conn = true;
      }
    }
  }
  if (!seen_file) throw InputError(path + ":1: not a VTK XML file (no <VTKFile> element)");
  const size_t last = w.line_at(data.size());
  if (!seen_piece) throw InputError(path + ":" + std::to_string(last) + ": no <Piece> element (truncated file?)");
  if (!closed) throw InputError(path + ":" + std::to_string(last) + ": no </VTKFile> (truncated file?)");
  if (!have_points) w.fail(piece_line, "Piece has no <Points> array");
  for (const Array* a : {&conn, &offsets, &types})
    if (!a->type.empty() && !is_integer_type(a->type))
      w.fail(a->line, "Cells array '" + a->name + "' has type " + a->type + ", expected an integer type");
  if (m > 0 && (!have_conn || !have_offsets || !have_types))
    w.fail(piece_line, "Piece lacks a Cells array (connectivity, offsets, types)");

  TetMesh mesh;
  mesh.vertices.resize(n, 3);
  std::copy(points.values.begin(), points.values.end(), mesh.vertices.data());
  std::vector<int> keep;
  long long prev = 0;
  for (long long c = 0; c < m; ++c) {
    const double off = offsets.values[static_cast<size_t>(c)];
    if (!(off >= prev) || off > static_cast<double>(conn.values.size()))
      w.fail(offsets.line, "cell " + std::to_string(c) + ": offset " + std::to_string(static_cast<long long>(off)) +
                               " is decreasing or beyond the " + std::to_string(conn.values.size()) +
                               " connectivity entries (wrong count)");
    const long long end = static_cast<long long>(off);
    const double type = types.values[static_cast<size_t>(c)];
    if (type == 10) {
      if (end - prev != 4)
        w.fail(offsets.line, "cell " + std::to_string(c) + ": tetrahedron (type 10) with " +
                                 std::to_string(end - prev) + " points");
      for (long long k = prev; k < end; ++k) {
        const double v = conn.values[static_cast<size_t>(k)];
        if (v < 0 || v >= static_cast<double>(n))
          w.fail(conn.line, "cell " + std::to_string(c) + ": point index " +
                                std::to_string(static_cast<long long>(v)) + " out of range 0.." +
                                std::to_string(n - 1) + (v == n ? " (indices look 1-based; VTK is 0-based)" : ""));
      }
      keep.push_back(static_cast<int>(c));
    }
    prev = end;
  }
  if (m > 0 && keep.empty())
    w.fail(piece_line, "none of the " + std::to_string(m) + " cells is a tetrahedron (VTK type 10)");
  mesh.tets.resize(static_cast<Eigen::Index>(keep.size()), 4);
  for (size_t t = 0; t < keep.size(); ++t) {
    const size_t start = keep[t] == 0 ? 0 : static_cast<size_t>(offsets.values[static_cast<size_t>(keep[t] - 1)]);
    for (int k = 0; k < 4; ++k)
      mesh.tets(static_cast<Eigen::Index>(t), k) = static_cast<int>(conn.values[start + static_cast<size_t>(k)]);
  }
  for (auto& a : point_fields) {
    if (a.name.empty()) w.fail(a.line, "point DataArray without a Name");
    FieldValues v(n, a.comps);
    std::copy(a.values.begin(), a.values.end(), v.data());
    mesh.set_point_field(a.name, std::move(v), is_integer_type(a.type));
  }
  for (auto& a : cell_fields) {
    if (a.name.empty()) w.fail(a.line, "cell DataArray without a Name");
    FieldValues v(static_cast<Eigen::Index>(keep.size()), a.comps);
    for (size_t t = 0; t < keep.size(); ++t)
      for (int k = 0; k < a.comps; ++k)
        v(static_cast<Eigen::Index>(t), k) = a.values[static_cast<size_t>(keep[t]) * a.comps + k];
    mesh.set_cell_field(a.name, std::move(v), is_integer_type(a.type));
  }
  return mesh;
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
