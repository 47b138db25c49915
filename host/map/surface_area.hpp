#pragma once
// Private: the face areas of a triangle surface and the chord triangles of a sphere map that face
// the centre (map/surface_checks.cpp), shared by the surface map and its metrics.
#include <Eigen/Core>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm::detail {

/// The area of each triangle of `faces` at positions `x`.
Eigen::VectorXd face_areas(const Points& x, const Triangles& faces);
/// The triangles whose chord triangle faces the centre: det(a, b, c) <= 0.
std::vector<int> flipped_list(const Points& x, const Triangles& faces);

}  // namespace vpm::detail
