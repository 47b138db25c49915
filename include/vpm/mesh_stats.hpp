#pragma once
// Size, topology, quality and volume of a tet mesh (what `vpm stats` prints), and the check that
// one mesh is a map of another (same vertices and tets, finite positions).
#include <string>

#include "vpm/json.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

struct MeshStats {
  int vertices = 0, tets = 0, boundary_faces = 0, edges = 0, faces = 0;
  int euler = 0;                ///< V - E + F - T of the tet complex (1 for a ball)
  int boundary_euler = 0;       ///< of the boundary surface (2 for a sphere)
  double min_dihedral_deg = 0;  ///< smallest dihedral angle
  int min_dihedral_tet = -1;    ///< the tet that has it (-1 without tets)
  double volume = 0;            ///< sum of the signed tet volumes
};

/// Statistics of `mesh` (validated: no face shared by more than two tets).
MeshStats mesh_stats(const TetMesh& mesh);

/// {"vertices", "tets", "boundary_faces", "euler", "boundary_euler", "min_dihedral_deg",
///  "min_dihedral_tet", "volume"}
Json to_json(const MeshStats& stats);

/// Checks that `mapped` (read from `mapped_name`) is a map of `reference` (from
/// `reference_name`): the same number of vertices and tets, tet t the same vertices as tet t of
/// `reference` or of `reference_tets_as_read` (before validation reoriented it), every position
/// finite. Throws InputError naming the file and the first tet or vertex that differs.
void check_map_of(const TetMesh& mapped, const std::string& mapped_name, const TetMesh& reference,
                  const Tets& reference_tets_as_read, const std::string& reference_name);

}  // namespace vpm
