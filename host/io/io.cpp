// File-format dispatch by extension; the formats live in host/io/<format>.cpp.
#include "vpm/io.hpp"

#include <algorithm>
#include <array>
#include <fstream>

#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace {
const char* kMeshExts = ".node/.ele (TetGen), .mesh (Medit), .vtu (VTK), .msh (Gmsh 4.1)";
const char* kSurfExts =
    ".off, .obj, .stl, .gii (GIfTI), .vtp (VTK PolyData), or a FreeSurfer surface (lh.white, lh.pial, lh.sphere, ...: recognised by its first bytes)";
const char* kSurfOutExts = ".off, .obj, .stl, .gii (GIfTI), .vtp (VTK PolyData with the fields), or a FreeSurfer name (.white, "
                           ".pial, .orig, .smoothwm, .inflated, .sphere, .reg, .midthickness, .surf)";
// FreeSurfer names its surfaces hemisphere.kind: these kinds are written in its binary format
constexpr std::array<const char*, 9> kFreeSurferKinds = {".white",   ".pial",   ".orig", ".smoothwm",    ".inflated",
                                                         ".sphere", ".reg", ".midthickness", ".surf"};

bool is_freesurfer_name(const std::string& e) {
  return std::any_of(kFreeSurferKinds.begin(), kFreeSurferKinds.end(), [&](const char* k) { return e == k; });
}

// The first bytes of `path` (fewer when it is shorter; none when it cannot be read).
std::string head_of(const std::string& path, size_t n) {
  std::ifstream in(path, std::ios::binary);
  std::string h(n, '\0');
  in.read(h.data(), static_cast<std::streamsize>(n));
  h.resize(static_cast<size_t>(std::max<std::streamsize>(0, in.gcount())));
  return h;
}
}  // namespace

bool is_mesh_path(const std::string& path) {
  const std::string e = detail::extension_of(path);
  return e == ".node" || e == ".ele" || e == ".mesh" || e == ".vtu" || e == ".msh";
}

bool is_surface_path(const std::string& path) {
  const std::string e = detail::extension_of(path);
  return e == ".off" || e == ".obj" || e == ".stl" || e == ".gii" || e == ".vtp" || is_freesurfer_name(e) ||
         detail::is_freesurfer_surface(head_of(path, 3));
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

Eigen::VectorXd read_overlay(const std::string& path) {
  const std::string e = detail::extension_of(path);
  if (e == ".gii") return detail::read_gifti_values(path);
  return detail::read_freesurfer_curv(path);
}

bool is_surface_output_path(const std::string& path) {
  const std::string e = detail::extension_of(path);
  return e == ".off" || e == ".obj" || e == ".stl" || e == ".vtp" || e == ".gii" || is_freesurfer_name(e);
}

TriSurface read_surface(const std::string& path) {
  const std::string e = detail::extension_of(path);
  if (e == ".off") return detail::read_off(path);
  if (e == ".obj") return detail::read_obj(path);
  if (e == ".stl") return detail::read_stl(path);
  if (e == ".gii") return detail::read_gifti(path);
  if (e == ".vtp") return detail::read_vtp(path);
  if (is_freesurfer_name(e) || detail::is_freesurfer_surface(head_of(path, 3))) return detail::read_freesurfer(path);
  throw InputError(path + ": unknown surface file extension '" + e + "' (expected " + kSurfExts +
                   ")");
}

void write_surface(const std::string& path, const TriSurface& surface) {
  const std::string e = detail::extension_of(path);
  detail::check_triangles(path, surface);
  if (e == ".off") return detail::write_off(path, surface);
  if (e == ".obj") return detail::write_obj(path, surface);
  if (e == ".stl") return detail::write_stl(path, surface, false);
  if (e == ".vtp") return detail::write_vtp(path, surface);
  if (e == ".gii") return detail::write_gifti(path, surface);
  if (is_freesurfer_name(e)) return detail::write_freesurfer(path, surface);
  throw InputError(path + ": unknown surface file extension '" + e + "' (expected " + kSurfOutExts + ")");
}

void write_surface_stl_binary(const std::string& path, const TriSurface& surface) {
  detail::check_triangles(path, surface);
  detail::write_stl(path, surface, true);
}

namespace detail {
void check_triangles(const std::string& path, const TriSurface& s) {
  for (Eigen::Index i = 0; i < s.triangles.rows(); ++i)
    for (int k = 0; k < 3; ++k)
      if (s.triangles(i, k) < 0 || s.triangles(i, k) >= s.vertices.rows())
        throw InputError(path + ": cannot write: triangle " + std::to_string(i) + " has vertex index " +
                         std::to_string(s.triangles(i, k)) + " out of range");
}

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
