#pragma once
// A memory-friendly numbering of a tet mesh: vertices and tets along a space-filling curve, so
// that the vertices of a tet, and the tets of a neighbourhood, lie close together in memory.
// Every sparse product, gather and scatter of the solvers, the AMG hierarchy, the polish and
// the advection then hits the cache far more often (measured in docs/solver.md).
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

/// Renumbers `mesh` in place: vertices in the Z-order (Morton order, 21 bits per axis over the
/// bounding box) of their positions, tets in the Z-order of their centroids (ties keep the old
/// order), each tet keeping its corner order (so its orientation). Every point and cell field is
/// permuted along. Returns the old index of each new vertex (`old_of_new[new] = old`).
std::vector<int> sort_spatially(TetMesh& mesh);

/// The rows of `points` in the Z-order of their positions over their bounding box (indices into
/// `points`; ties keep the old order): neighbours in space become neighbours in the list.
std::vector<int> spatial_order(const Points& points);

}  // namespace vpm
