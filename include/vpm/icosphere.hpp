#pragma once
// The icosahedral subdivision of the unit sphere: the triangulation the canonical volume
// elements of the collective analysis are built on (20 * 4^level spherical triangles), and a
// closed test surface.
#include "vpm/mesh.hpp"

namespace vpm {

/// The regular icosahedron on the unit sphere, each triangle split `level` times into four at
/// its edge midpoints, the new vertices projected to the sphere. 10 * 4^level + 2 vertices
/// (the icosahedron's 12 first, then each subdivision's midpoints in order of creation) and
/// 20 * 4^level triangles, oriented with outward normals; deterministic. level in 0..10
/// (InputError otherwise).
TriSurface icosphere(int level);

}  // namespace vpm
