#pragma once
// Mesh and surface file formats, chosen by file extension.
//
// Tet meshes: TetGen .node/.ele (either name gives the pair; .face ignored on read, written
// with the boundary), Medit .mesh, VTK .vtu (XML; fields as point and cell data; read in ASCII
// and every binary form, written as appended raw binary or ASCII), Gmsh .msh 4.1 ASCII. Surfaces: .off, .obj, .stl (ASCII or binary).
//
// Readers throw InputError("FILE:LINE: problem") on malformed input (truncated, wrong counts,
// text in numbers, 1-based/0-based confusion, counts larger than the file could hold) and
// never allocate more than the file size justifies. Writers write to a temporary name in the
// same folder and rename, so a failed write leaves no partial file.
#include <string>

#include "vpm/mesh.hpp"

namespace vpm {

/// Reads a tet mesh (fields too, where the format carries them). Does not validate topology:
/// call validate_mesh() for that.
TetMesh read_mesh(const std::string& path);

/// How write_mesh() encodes a .vtu file's arrays: `binary` appends them as raw little-endian
/// bytes (`<AppendedData encoding="raw">`, as ParaView writes; the default), `ascii` writes
/// decimal text in the XML. Both are exact (Float64 and Int32).
enum class VtuEncoding { binary, ascii };

/// Writes a tet mesh; .vtu writes all fields (binary, see VtuEncoding), other formats write
/// geometry (and a `label` cell field as the element reference/region tag where the format
/// has one).
void write_mesh(const std::string& path, const TetMesh& mesh);
/// The same, with the encoding of a .vtu file chosen (ignored for other formats).
void write_mesh(const std::string& path, const TetMesh& mesh, VtuEncoding encoding);

/// Reads a triangle surface: .off, .obj, .stl, .gii (GIfTI), .vtp (VTK PolyData of triangles, its
/// point and cell fields into point_data and cell_data) by extension, FreeSurfer's binary triangle
/// surfaces (lh.white, lh.pial, ...) by their first bytes (FF FF FE) or FreeSurfer's names
/// (.white, .pial, .orig, .smoothwm, .inflated, .sphere, .reg, .midthickness, .surf).
TriSurface read_surface(const std::string& path);

/// Writes a triangle surface: .off, .obj, .stl, .gii (GIfTI: float32, base64 of gzip), .vtp
/// (VTK XML PolyData with the surface's point and cell fields), FreeSurfer's binary format under FreeSurfer's names (float32
/// coordinates). STL is written as ASCII with exact decimal coordinates; use
/// write_surface_stl_binary() for the compact (float) form.
void write_surface(const std::string& path, const TriSurface& surface);

/// Writes binary STL (coordinates rounded to float, normals from the triangles).
void write_surface_stl_binary(const std::string& path, const TriSurface& surface);

/// Per-vertex values of a surface (an overlay): GIfTI's .shape.gii / .func.gii (its first DataArray
/// of one value a vertex), else FreeSurfer's per-vertex files (lh.curv, lh.thickness, lh.sulc).
Eigen::VectorXd read_overlay(const std::string& path);

/// True if write_surface() writes `path` (by its extension).
bool is_surface_output_path(const std::string& path);
/// True if `path` has an extension read_mesh() understands.
bool is_mesh_path(const std::string& path);
/// True if read_surface() reads `path`: by its extension, or a FreeSurfer surface by its first
/// bytes.
bool is_surface_path(const std::string& path);

}  // namespace vpm
