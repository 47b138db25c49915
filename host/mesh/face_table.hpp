#pragma once
// Private: the faces of a tet mesh matched by their vertices, the one sort behind boundary
// faces, non-manifold faces and face neighbours (vpm/topology.hpp, mesh/tet_grid.hpp).
#include <cstdint>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm::detail {

/// Face k of tet t is the one opposite corner k; slot = 4 t + k.
/// Every slot of the mesh, ordered by the face's sorted vertex triple (lexicographically), equal
/// triples adjacent and by slot. Built by a counting sort on the smallest vertex and a sort of
/// each vertex's short list (host threads): linear in the mesh.
struct FaceTable {
  struct Entry {
    std::uint64_t rest;  ///< the two larger vertices: (middle << 32) | largest
    int slot;
  };
  std::vector<int> start;     ///< n + 1: the entries whose smallest vertex is v: [start[v], start[v+1])
  std::vector<Entry> entries; ///< 4 m

  /// Calls group(first, count) for each run of entries with the same triple, in order.
  template <class Fn>
  void for_each_group(Fn group) const {
    const int n = static_cast<int>(start.size()) - 1;
    for (int v = 0; v < n; ++v)
      for (int i = start[static_cast<size_t>(v)], e = start[static_cast<size_t>(v) + 1]; i < e;) {
        int j = i + 1;
        while (j < e && entries[static_cast<size_t>(j)].rest == entries[static_cast<size_t>(i)].rest) ++j;
        group(i, j - i);
        i = j;
      }
  }
};

FaceTable face_table(const Tets& tets);

/// vpm::boundary_faces and vpm::nonmanifold_faces (vpm/topology.hpp) from a table already built,
/// for callers that need more than one answer from the same tets (one sort instead of several).
Triangles boundary_faces(const FaceTable& table, const Tets& tets, std::vector<int>* face_tet = nullptr);
int nonmanifold_faces(const FaceTable& table);

}  // namespace vpm::detail
