#pragma once
// Private: the face areas of a triangle surface and the chord triangles of a sphere map that face
// the centre (map/surface_checks.cpp), shared by the surface map and its metrics.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/surface_map.hpp"

namespace vpm::detail {

/// The area of each triangle of `faces` at positions `x`.
Eigen::VectorXd face_areas(const Points& x, const Triangles& faces);
/// The flipped triangles of a map onto `domain`: on the sphere those whose chord triangle faces
/// the centre (det(a, b, c) <= 0), in the disk those turned clockwise (z of (b - a) x (c - a) <= 0).
std::vector<int> flipped_faces_in(SurfaceDomain domain, const Points& x, const Triangles& faces);

/// The open edges of `faces` (edges of one face) as one ordered loop of vertices, running so
/// that the faces are on its left (counter-clockwise around a disk whose faces are); empty when
/// there are none. InputError naming `what` when they form more than one loop or a vertex is on
/// the boundary twice.
std::vector<int> boundary_loop(int n, const Triangles& faces, const std::string& what);
/// 1 on boundary_loop's vertices (n entries).
std::vector<char> loop_mask(int n, const Triangles& faces);

}  // namespace vpm::detail
