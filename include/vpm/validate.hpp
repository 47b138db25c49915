#pragma once
// Validation of an input tet mesh, with one precise message per problem.
#include <string>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

/// What validation found and fixed.
/// Dihedral angle (degrees) below which a tet counts as a sliver.
constexpr double kSliverDihedralDeg = 2.0;

struct ValidationReport {
  int reoriented_tets = 0;   ///< negatively oriented tets fixed by swapping two vertices
  int boundary_faces = 0;
  int boundary_vertices = 0;
  int boundary_euler = 0;    ///< Euler characteristic of the boundary surface (2 for a sphere)
  double min_dihedral_deg = 0;  ///< smallest dihedral angle over all tets
  int min_dihedral_tet = -1;    ///< tet where it occurs
  /// Tets with a dihedral angle below kSliverDihedralDeg: slivers, which make the map fold or
  /// stall (remesh such an input: docs/volume_map.md "Slivers").
  int sliver_tets = 0;
  std::vector<std::string> notes;  ///< human-readable remarks (fixes made)
};

struct ValidateOptions {
  /// Require the boundary to be one closed genus-0 surface (the ball-map precondition).
  bool require_ball_topology = true;
  /// Tets whose |signed volume| is below this fraction of the mean |volume| count as degenerate.
  double degenerate_relative_volume = 1e-12;
};

/// Checks `mesh` and throws InputError("SOURCE: tet 17: ...") at the first problem:
/// vertex index out of range, non-finite coordinate, isolated vertex, degenerate tet
/// (repeated vertex or ~zero volume), duplicate tet, face shared by more than two tets,
/// non-manifold boundary (edge or vertex), several connected components, boundary not a single
/// closed genus-0 surface. Negatively oriented tets are fixed in place (two vertices swapped)
/// and counted. `source` names the file in messages.
ValidationReport validate_mesh(TetMesh& mesh, const std::string& source,
                               const ValidateOptions& options = {});

}  // namespace vpm
