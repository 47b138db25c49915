// File-format dispatch by extension; the formats live in host/io_<format>.cpp.
#include "vpm/io.hpp"

#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace {
const char* kMeshExts = ".node/.ele (TetGen), .mesh (Medit), .vtu (VTK), .msh (Gmsh 4.1)";
const char* kSurfExts = ".off, .obj, .stl";
}  // namespace

bool is_mesh_path(const std::string& path) {
  const std::string e = detail::extension_of(path);
  return e == ".node" || e == ".ele" || e == ".mesh" || e == ".vtu" || e == ".msh";
}

bool is_surface_path(const std::string& path) {
  const std::string e = detail::extension_of(path);
  return e == ".off" || e == ".obj" || e == ".stl";
}

TetMesh read_mesh(const std::string& path) {
  const std::string e = detail::extension_of(path);
  if (e == ".node" || e == ".ele") return detail::read_tetgen(path);
  if (e == ".mesh") return detail::read_medit(path);
  if (e == ".vtu") return detail::read_vtu(path);
  if (e == ".msh") return detail::read_gmsh(path);
  throw InputError(path + ": unknown mesh file extension '" + e + "' (expected " + kMeshExts + ")");
}

void write_mesh(const std::string& path, const TetMesh& mesh) { write_mesh(path, mesh, VtuEncoding::binary); }

void write_mesh(const std::string& path, const TetMesh& mesh, VtuEncoding encoding) {
  const std::string e = detail::extension_of(path);
  if (!is_mesh_path(path))
    throw InputError(path + ": unknown mesh file extension '" + e + "' (expected " + kMeshExts +
                     ")");
  detail::check_fields(path, mesh);
  if (e == ".node" || e == ".ele") return detail::write_tetgen(path, mesh);
  if (e == ".mesh") return detail::write_medit(path, mesh);
  if (e == ".vtu")
    return encoding == VtuEncoding::ascii ? detail::write_vtu(path, mesh) : detail::write_vtu_binary(path, mesh);
  return detail::write_gmsh(path, mesh);
}

TriSurface read_surface(const std::string& path) {
  const std::string e = detail::extension_of(path);
  if (e == ".off") return detail::read_off(path);
  if (e == ".obj") return detail::read_obj(path);
  if (e == ".stl") return detail::read_stl(path);
  throw InputError(path + ": unknown surface file extension '" + e + "' (expected " + kSurfExts +
                   ")");
}

void write_surface(const std::string& path, const TriSurface& surface) {
  const std::string e = detail::extension_of(path);
  if (e == ".off") return detail::write_off(path, surface);
  if (e == ".obj") return detail::write_obj(path, surface);
  if (e == ".stl") return detail::write_stl(path, surface, false);
  throw InputError(path + ": unknown surface file extension '" + e + "' (expected " + kSurfExts +
                   ")");
}

void write_surface_stl_binary(const std::string& path, const TriSurface& surface) {
  detail::write_stl(path, surface, true);
}

namespace detail {
void check_fields(const std::string& path, const TetMesh& mesh) {
  for (const auto& f : mesh.point_data)
    if (f.values.rows() != mesh.vertices.rows())
      throw InputError(path + ": cannot write point field '" + f.name + "': " +
                       std::to_string(f.values.rows()) + " rows for " +
                       std::to_string(mesh.vertices.rows()) + " vertices");
  for (const auto& f : mesh.cell_data)
    if (f.values.rows() != mesh.tets.rows())
      throw InputError(path + ": cannot write cell field '" + f.name + "': " +
                       std::to_string(f.values.rows()) + " rows for " +
                       std::to_string(mesh.tets.rows()) + " tets");
}
}  // namespace detail

}  // namespace vpm
