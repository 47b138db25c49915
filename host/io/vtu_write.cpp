// Writing VTK XML UnstructuredGrid (.vtu) as ASCII (VtuEncoding::ascii; the binary form is in
// vtu_write_binary.cpp): points, tets (VTK type 10) and every point/cell
// field (Int32 for integer fields, Float64 otherwise). The reader is in vtu.cpp.
#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "io/xml.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

void open_vtu_piece(TextOut& o, std::string_view vtkfile_attributes, long long n, long long m) {
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" " << vtkfile_attributes
    << ">\n  <UnstructuredGrid>\n    <Piece NumberOfPoints=\"";
  o.integer(n) << "\" NumberOfCells=\"";
  o.integer(m) << "\">\n";
}

void write_ascii_fields(TextOut& o, const char* section, const std::vector<Field>& fs) {
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
}

void write_vtu(const std::string& path, const TetMesh& mesh) {
  AtomicFile file(path);
  TextOut o(file.stream());
  const long long n = mesh.num_vertices(), m = mesh.num_tets();
  open_vtu_piece(o, "version=\"0.1\" byte_order=\"LittleEndian\"", n, m);
  write_ascii_fields(o, "PointData", mesh.point_data);
  write_ascii_fields(o, "CellData", mesh.cell_data);
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
