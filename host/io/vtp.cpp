// Writing VTK XML PolyData (.vtp) as ASCII: points, triangles (Polys) and the surface's point and
// cell fields, as ParaView and VTK's vtkXMLPolyDataReader read them.
#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

void write_vtp(const std::string& path, const TriSurface& s) {
  const long long n = s.vertices.rows(), m = s.triangles.rows();
  for (const Field& f : s.point_data)
    if (f.values.rows() != n)
      throw InputError(path + ": cannot write point field '" + f.name + "': " + std::to_string(f.values.rows()) +
                       " rows for " + std::to_string(n) + " vertices");
  for (const Field& f : s.cell_data)
    if (f.values.rows() != m)
      throw InputError(path + ": cannot write cell field '" + f.name + "': " + std::to_string(f.values.rows()) +
                       " rows for " + std::to_string(m) + " triangles");
  AtomicFile file(path);
  TextOut o(file.stream());
  o << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
       "  <PolyData>\n    <Piece NumberOfPoints=\"";
  o.integer(n) << "\" NumberOfVerts=\"0\" NumberOfLines=\"0\" NumberOfStrips=\"0\" NumberOfPolys=\"";
  o.integer(m) << "\">\n";
  write_ascii_fields(o, "PointData", s.point_data);
  write_ascii_fields(o, "CellData", s.cell_data);
  o << "      <Points>\n"
       "        <DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (long long i = 0; i < n; ++i) {
    o.real(s.vertices(i, 0)) << ' ';
    o.real(s.vertices(i, 1)) << ' ';
    o.real(s.vertices(i, 2)) << '\n';
  }
  o << "        </DataArray>\n      </Points>\n      <Polys>\n"
       "        <DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (long long i = 0; i < m; ++i) {
    o.integer(s.triangles(i, 0)) << ' ';
    o.integer(s.triangles(i, 1)) << ' ';
    o.integer(s.triangles(i, 2)) << '\n';
  }
  o << "        </DataArray>\n        <DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (long long i = 0; i < m; ++i) o.integer(3 * (i + 1)) << ((i % 16 == 15 || i + 1 == m) ? '\n' : ' ');
  o << "        </DataArray>\n      </Polys>\n    </Piece>\n  </PolyData>\n</VTKFile>\n";
  o.flush();
  file.commit();
}

}  // namespace vpm::detail
