#include "vpm/mesh_stats.hpp"

#include <cmath>

#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

namespace vpm {

MeshStats mesh_stats(const TetMesh& m) {
  MeshStats s;
  s.vertices = m.num_vertices();
  s.tets = m.num_tets();
  const Triangles bf = boundary_faces(m.tets);
  s.boundary_faces = static_cast<int>(bf.rows());
  s.edges = static_cast<int>(unique_edges(m.tets).rows());
  // Every interior face is shared by two tets, every boundary face belongs to one
  // (faces shared by more than two tets are rejected by validation).
  s.faces = (4 * s.tets + s.boundary_faces) / 2;
  s.euler = s.vertices - s.edges + s.faces - s.tets;
  s.boundary_euler = surface_topology(s.vertices, bf).euler;
  if (s.tets > 0) {
    const auto angles = dihedral_angles_deg(m.vertices, m.tets);
    Eigen::Index r = 0, c = 0;
    s.min_dihedral_deg = angles.minCoeff(&r, &c);
    s.min_dihedral_tet = static_cast<int>(r);
  }
  s.volume = tet_volumes(m.vertices, m.tets).sum();
  return s;
}

Json to_json(const MeshStats& s) {
  Json m = Json::object();
  m["vertices"] = s.vertices;
  m["tets"] = s.tets;
  m["boundary_faces"] = s.boundary_faces;
  m["euler"] = s.euler;
  m["boundary_euler"] = s.boundary_euler;
  m["min_dihedral_deg"] = s.min_dihedral_deg;
  m["min_dihedral_tet"] = s.min_dihedral_tet;
  m["volume"] = s.volume;
  return m;
}

void check_map_of(const TetMesh& mesh, const std::string& path, const TetMesh& ref, const Tets& as_read,
                  const std::string& ref_path) {
  if (mesh.num_vertices() != ref.num_vertices())
    throw InputError(path + ": has " + std::to_string(mesh.num_vertices()) + " vertices but " + ref_path +
                     " has " + std::to_string(ref.num_vertices()) + " (not a map of it)");
  if (mesh.num_tets() != ref.num_tets())
    throw InputError(path + ": has " + std::to_string(mesh.num_tets()) + " tets but " + ref_path + " has " +
                     std::to_string(ref.num_tets()) + " (not a map of it)");
  for (int t = 0; t < mesh.num_tets(); ++t)
    if (mesh.tets.row(t) != as_read.row(t) && mesh.tets.row(t) != ref.tets.row(t))
      throw InputError(path + ": tet " + std::to_string(t) + " differs from tet " + std::to_string(t) + " of " +
                       ref_path + " (a map has the same tets)");
  for (Eigen::Index i = 0; i < mesh.vertices.size(); ++i)
    if (!std::isfinite(mesh.vertices.data()[i]))
      throw InputError(path + ": vertex " + std::to_string(i / 3) + ": non-finite coordinate");
}

}  // namespace vpm
