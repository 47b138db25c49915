// Writing VTK XML UnstructuredGrid (.vtu) with its arrays appended as raw little-endian binary
// (`<AppendedData encoding="raw">`, UInt64 block headers), the form ParaView writes without
// compression: bit-exact like the ASCII form (vtu_write.cpp), a third of the bytes for the
// connectivity, and read without parsing text. The reader (vtu.cpp, vtk_binary.cpp) reads both.
#include <bit>
#include <cmath>
#include <cstdint>
#include <functional>
#include <vector>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "io/xml.hpp"

namespace vpm::detail {

static_assert(std::endian::native == std::endian::little, "the appended .vtu writer writes the host's bytes");

namespace {

// One array of the appended block: its XML attributes and a writer of its bytes.
struct Block {
  std::string type, name;
  long long components = 1;
  std::uint64_t bytes = 0;
  std::function<void(std::ostream&)> write;
};

template <class T>
void write_raw(std::ostream& out, const T* data, size_t count) {
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(count * sizeof(T)));
}

// Writes `count` values of type T produced by value(i), in chunks of 64k.
template <class T, class F>
void write_generated(std::ostream& out, size_t count, F value) {
  std::vector<T> buf;
  buf.reserve(65536);
  for (size_t i = 0; i < count; ++i) {
    buf.push_back(value(i));
    if (buf.size() == 65536 || i + 1 == count) {
      write_raw(out, buf.data(), buf.size());
      buf.clear();
    }
  }
}

Block field_block(const Field& f) {
  Block b{f.integer ? "Int32" : "Float64", f.name, f.values.cols(), 0, {}};
  const size_t count = static_cast<size_t>(f.values.size());
  b.bytes = count * (f.integer ? 4 : 8);
  const FieldValues* v = &f.values;  // row-major: components of a row are adjacent
  if (f.integer)
    b.write = [v, count](std::ostream& o) {
      write_generated<std::int32_t>(o, count, [v](size_t i) {
        return static_cast<std::int32_t>(std::llround(v->data()[i]));
      });
    };
  else
    b.write = [v, count](std::ostream& o) { write_raw(o, v->data(), count); };
  return b;
}

void write_header(TextOut& o, const std::vector<Block>& blocks, size_t point_fields, size_t cell_fields,
                  long long n, long long m) {
  open_vtu_piece(o, "version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\"", n, m);
  std::uint64_t offset = 0;
  size_t next = 0;
  auto arrays = [&](const char* section, size_t count) {
    o << "      <" << section << ">\n";
    for (size_t k = 0; k < count; ++k, ++next) {
      const Block& b = blocks[next];
      o << "        <DataArray type=\"" << b.type.c_str() << "\" Name=\"" << xml_escape(b.name) << "\"";
      if (b.components != 1) {
        o << " NumberOfComponents=\"";
        o.integer(b.components) << "\"";
      }
      o << " format=\"appended\" offset=\"";
      o.integer(static_cast<long long>(offset)) << "\"/>\n";
      offset += 8 + b.bytes;
    }
    o << "      </" << section << ">\n";
  };
  arrays("PointData", point_fields);
  arrays("CellData", cell_fields);
  arrays("Points", 1);
  arrays("Cells", 3);
  o << "    </Piece>\n"
       "  </UnstructuredGrid>\n"
       "  <AppendedData encoding=\"raw\">\n"
       "   _";
}

}  // namespace

void write_vtu_binary(const std::string& path, const TetMesh& mesh) {
  const long long n = mesh.num_vertices(), m = mesh.num_tets();
  std::vector<Block> blocks;
  for (const Field& f : mesh.point_data) blocks.push_back(field_block(f));
  for (const Field& f : mesh.cell_data) blocks.push_back(field_block(f));
  blocks.push_back({"Float64", "Points", 3, static_cast<std::uint64_t>(3 * n) * 8,
                    [&](std::ostream& o) { write_raw(o, mesh.vertices.data(), static_cast<size_t>(3 * n)); }});
  blocks.push_back({"Int32", "connectivity", 1, static_cast<std::uint64_t>(4 * m) * 4,
                    [&](std::ostream& o) { write_raw(o, mesh.tets.data(), static_cast<size_t>(4 * m)); }});
  blocks.push_back({"Int64", "offsets", 1, static_cast<std::uint64_t>(m) * 8, [&](std::ostream& o) {
                      write_generated<std::int64_t>(o, static_cast<size_t>(m),
                                                    [](size_t i) { return static_cast<std::int64_t>(4 * (i + 1)); });
                    }});
  blocks.push_back({"UInt8", "types", 1, static_cast<std::uint64_t>(m), [&](std::ostream& o) {
                      write_generated<std::uint8_t>(o, static_cast<size_t>(m), [](size_t) { return std::uint8_t{10}; });
                    }});
  AtomicFile file(path, true);
  std::ostream& out = file.stream();
  {
    TextOut o(out);
    write_header(o, blocks, mesh.point_data.size(), mesh.cell_data.size(), n, m);
    o.flush();
  }
  for (const Block& b : blocks) {
    write_raw(out, &b.bytes, 1);
    b.write(out);
  }
  out << "\n  </AppendedData>\n</VTKFile>\n";
  file.commit();
}

}  // namespace vpm::detail
