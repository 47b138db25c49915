#pragma once
// Private: one reader/writer pair per file format (host/io/<format>.cpp); io.cpp dispatches.
#include <string>
#include <string_view>

#include "vpm/mesh.hpp"

namespace vpm::detail {

class TextOut;

TetMesh read_tetgen(const std::string& path);   // .node or .ele: reads the pair
void write_tetgen(const std::string& path, const TetMesh& mesh);  // .node + .ele + .face
TetMesh read_medit(const std::string& path);
void write_medit(const std::string& path, const TetMesh& mesh);
TetMesh read_vtu(const std::string& path);
TriSurface read_vtp(const std::string& path);
void write_vtu(const std::string& path, const TetMesh& mesh);         // ASCII (vtu_write.cpp)
/// Writes the XML declaration and the opening VTKFile (with `vtkfile_attributes` after its
/// type), UnstructuredGrid and Piece tags of a .vtu for n points and m cells (vtu_write.cpp).
void open_vtu_piece(TextOut& o, std::string_view vtkfile_attributes, long long n, long long m);
/// The <PointData> or <CellData> section (`section`) of a VTK XML piece with `fields` as ASCII
/// DataArrays (Int32 for integer fields, Float64 otherwise; vtu_write.cpp).
void write_ascii_fields(TextOut& o, const char* section, const std::vector<Field>& fields);
void write_vtu_binary(const std::string& path, const TetMesh& mesh);  // appended raw (vtu_write_binary.cpp)
TetMesh read_gmsh(const std::string& path);
void write_gmsh(const std::string& path, const TetMesh& mesh);

TriSurface read_off(const std::string& path);
void write_off(const std::string& path, const TriSurface& surface);
TriSurface read_obj(const std::string& path);
void write_obj(const std::string& path, const TriSurface& surface);
TriSurface read_stl(const std::string& path);
void write_stl(const std::string& path, const TriSurface& surface, bool binary);
/// FreeSurfer's binary triangle surface (freesurfer.cpp); `head` = the file's first bytes.
bool is_freesurfer_surface(const std::string& head);
TriSurface read_freesurfer(const std::string& path);
void write_freesurfer(const std::string& path, const TriSurface& surface);
/// FreeSurfer's per-vertex file (.curv, .thickness, .sulc; freesurfer.cpp).
Eigen::VectorXd read_freesurfer_curv(const std::string& path);
/// GIfTI surfaces (.gii; host/with_gifti/ through expat, or io/gifti_missing.cpp).
TriSurface read_gifti(const std::string& path);
void write_gifti(const std::string& path, const TriSurface& surface);
/// A GIfTI per-vertex file (.shape.gii, .func.gii): its first DataArray of one value a vertex.
Eigen::VectorXd read_gifti_values(const std::string& path);
/// VTK XML PolyData, ASCII, with the surface's point and cell fields (vtp.cpp; written only).
void write_vtp(const std::string& path, const TriSurface& surface);

/// Checks that every triangle's vertex indices are rows of the surface's vertices, before any
/// writer writes it (write_surface, write_surface_stl_binary) (InputError naming `path` and the first bad triangle).
void check_triangles(const std::string& path, const TriSurface& surface);

/// Checks that the mesh's fields have the right number of rows (InputError naming `path`).
void check_fields(const std::string& path, const TetMesh& mesh);

}  // namespace vpm::detail
