#pragma once
// Combinatorial queries on tet meshes: boundary faces, boundary vertices, edges, incidence,
// connected components, Euler characteristic. Host only: the host owns topology.
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

/// Boundary triangles of a tet mesh: faces that belong to exactly one tet, oriented so that
/// their normal points out of that tet (outward for positively oriented tets).
/// `face_tet`, if given, receives for each face the index of the tet it belongs to.
/// Faces shared by three or more tets are not returned; count them with nonmanifold_faces().
Triangles boundary_faces(const Tets& tets, std::vector<int>* face_tet = nullptr);

/// The boundary of a tet mesh as a surface: boundary_faces over the vertices they use
/// (renumbered in increasing order of the mesh's vertex ids), outward for positive tets.
TriSurface boundary_surface(const TetMesh& mesh);

/// What every stage that walks or restores a tet mesh reads and none changes: the face
/// neighbours, the boundary faces and the boundary vertices, from one sort of the 4m faces.
/// Built once per mesh and passed down (TetLocator, the dense registration) instead of each
/// call re-deriving them from the tets.
struct TetTopology {
  std::vector<int> neighbours;        ///< 4m: the tet across the face opposite corner k of tet t, or -1
  Triangles boundary;                 ///< boundary_faces(tets)
  std::vector<char> boundary_vertex;  ///< boundary_vertex_mask(num_vertices, boundary)
};
TetTopology tet_topology(int num_vertices, const Tets& tets);

/// Number of triangles shared by more than two tets (0 for a manifold tet mesh).
int nonmanifold_faces(const Tets& tets);

/// For each of the `num_vertices` vertices, 1 if it lies on a triangle of `faces`.
std::vector<char> boundary_vertex_mask(int num_vertices, const Triangles& faces);

/// Unique undirected edges (i < j) of a tet mesh, sorted lexicographically. k x 2.
Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> unique_edges(const Tets& tets);

/// Compressed vertex -> tet incidence: tets touching vertex v are
/// `tet_of[offset[v] .. offset[v+1])`, in increasing order; `offset` has n+1 entries.
struct Incidence {
  std::vector<int> offset;
  std::vector<int> tet_of;
};
Incidence vertex_tet_incidence(int num_vertices, const Tets& tets);

/// The vertices of `seed_tets` and of every tet within `rings` rings of them (1 = the seeds'
/// vertices and those of the tets touching them, ...): a mask of num_vertices entries. One pass
/// over the tets a ring, no incidence built. Seed indices must be in range.
std::vector<char> vertices_near_tets(int num_vertices, const Tets& tets, const std::vector<int>& seed_tets, int rings);

/// Connected components of the vertices that tets join (isolated vertices are their own
/// component). Returns the component id of each vertex; `count` receives the number.
std::vector<int> vertex_components(int num_vertices, const Tets& tets, int* count);

/// Topological summary of a closed triangle surface.
struct SurfaceTopology {
  int vertices = 0;          ///< vertices used by at least one triangle
  int edges = 0;
  int faces = 0;
  int euler = 0;             ///< V - E + F (2 for one sphere)
  int components = 0;        ///< edge-connected components
  int open_edges = 0;        ///< edges with one incident triangle (0 when closed)
  int nonmanifold_edges = 0; ///< edges with three or more incident triangles
  int nonmanifold_vertices = 0;  ///< vertices whose triangle fan is not one disk
  int first_bad_vertex = -1; ///< index of a non-manifold vertex, or -1
  int first_bad_edge[2] = {-1, -1};  ///< an open or non-manifold edge, or -1
  /// Genus of a closed connected surface: (2 - euler) / 2.
  int genus() const { return (2 - euler) / 2; }
};
SurfaceTopology surface_topology(int num_vertices, const Triangles& faces);

}  // namespace vpm
