#pragma once
// Fields carried between two tet meshes of the same solid. Two meshes of one subject (a coarse
// and a fine one, meshed from the same image, each with its own map to the ball) share their
// native space, so a per-vertex field of one (its registered ball positions, a displacement, a
// feature) is known at every native point by the barycentric combination of the tet holding it,
// and so at the other mesh's vertices: a registration found on a coarse mesh is carried to a fine
// one (docs/register.md, "Across meshes").
#include <Eigen/Core>

#include "vpm/locate.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// `values` (one row per vertex of the mesh `from` locates in, any number of columns) at
/// `points` (k x 3, in the space of from's vertices): each point's barycentric combination of the
/// values at the vertices of its tet, so a field linear over the mesh is carried exactly. A point
/// outside the mesh (the boundary vertices of another mesh inscribed in the same surface lie up
/// to a fraction of an edge outside) takes the combination at the closest point of the boundary
/// tet the search ends in.
/// InputError when `values` has fewer rows than the tets' largest vertex. Host threads.
Eigen::MatrixXd carry_vertex_field(const TetLocator& from, const Eigen::MatrixXd& values, const Points& points);

/// A registration carried onto another mesh (carry_registration).
struct CarriedRegistration {
  Points ball;       ///< the target mesh's ball positions (n x 3)
  int folded = 0;    ///< target tets the carrying inverted, before they were untangled
  int inverted = 0;  ///< target tets still inverted at the end (0 unless untangling failed)
};

/// A registration (or any map to the ball) of one mesh carried onto another mesh of the same
/// solid: the vertices of `target`, at their native positions (its point field
/// original_position), located in `source`'s native mesh (its original_position) and placed at
/// the same barycentric combination of `source`'s ball positions (its vertices); target's
/// boundary vertices then put back on the unit sphere (radially). Where the source map is smooth
/// the result is within its interpolation error of it; where target's tets are much smaller than
/// source's and the map bends, some fold (223 of 220k carrying a paper-size registration onto a
/// 45,000-vertex mesh of the same brain): those are untangled locally (flipped sphere faces
/// first, then untangle_local with 2, 4, ... 32 rings, boundary fixed, target's own map as the
/// reference); `inverted` says what is left. InputError when either mesh lacks
/// original_position.
CarriedRegistration carry_registration(const TetMesh& source, const TetMesh& target);

}  // namespace vpm
