#pragma once
// The tetrahedral mesh model shared by every stage, its fields, and triangle surfaces.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace vpm {

/// n x 3 vertex coordinates (row-major: one vertex a row), any length unit (mm for images).
using Points = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// m x 4 vertex indices of tetrahedra, 0-based, positively oriented after validation
/// (signed volume of (v1-v0, v2-v0, v3-v0) > 0).
using Tets = Eigen::Matrix<int, Eigen::Dynamic, 4, Eigen::RowMajor>;
/// k x 3 vertex indices of triangles, 0-based.
using Triangles = Eigen::Matrix<int, Eigen::Dynamic, 3, Eigen::RowMajor>;
/// Row-major dense matrix used for attached data (one element a row, one component a column).
using FieldValues = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// A named array attached to vertices (point data) or tets (cell data).
struct Field {
  std::string name;     ///< e.g. "vertex_volume_ratio", "original_position", "label"
  FieldValues values;   ///< rows = number of vertices or tets, cols = components (1 or 3)
  bool integer = false; ///< written as Int32 where the format distinguishes (labels)
};

/// A tetrahedral mesh with optional fields.
struct TetMesh {
  Points vertices;
  Tets tets;
  std::vector<Field> point_data;  ///< each with vertices.rows() rows
  std::vector<Field> cell_data;   ///< each with tets.rows() rows

  int num_vertices() const { return static_cast<int>(vertices.rows()); }
  int num_tets() const { return static_cast<int>(tets.rows()); }
  /// The point/cell field of that name, or nullptr.
  const Field* find_point_field(const std::string& name) const;
  const Field* find_cell_field(const std::string& name) const;
  /// Adds or replaces a field. `values` must have the matching number of rows.
  void set_point_field(const std::string& name, FieldValues values, bool integer = false);
  void set_cell_field(const std::string& name, FieldValues values, bool integer = false);
};

/// The native positions of a mapped mesh's vertices: its point field original_position (n x 3),
/// which `vpm map` writes (each vertex's position in the input mesh). InputError
/// "`what`: no point field original_position (3 components): ..." when it is missing.
Points native_positions(const TetMesh& mapped, const std::string& what);

/// A triangle surface (input to meshing, a mesh boundary, or a surface mapped to the sphere).
struct TriSurface {
  Points vertices;
  Triangles triangles;  ///< oriented with outward normals for closed surfaces
  /// Fields, written where the format carries them (.vtp): point data one row a vertex, cell
  /// data one row a triangle (e.g. "original_position", "face_area_ratio").
  std::vector<Field> point_data, cell_data;
};

}  // namespace vpm
