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
void write_vtu(const std::string& path, const TetMesh& mesh);         // ASCII (vtu_write.cpp)
/// Writes the XML declaration and the opening VTKFile (with `vtkfile_attributes` after its
/// type), UnstructuredGrid and Piece tags of a .vtu for n points and m cells (vtu_write.cpp).
void open_vtu_piece(TextOut& o, std::string_view vtkfile_attributes, long long n, long long m);
void write_vtu_binary(const std::string& path, const TetMesh& mesh);  // appended raw (vtu_write_binary.cpp)
TetMesh read_gmsh(const std::string& path);
void write_gmsh(const std::string& path, const TetMesh& mesh);

TriSurface read_off(const std::string& path);
void write_off(const std::string& path, const TriSurface& surface);
TriSurface read_obj(const std::string& path);
void write_obj(const std::string& path, const TriSurface& surface);
TriSurface read_stl(const std::string& path);
void write_stl(const std::string& path, const TriSurface& surface, bool binary);

/// Checks that the mesh's fields have the right number of rows (InputError naming `path`).
void check_fields(const std::string& path, const TetMesh& mesh);

}  // namespace vpm::detail
