#pragma once
// Mean curvature of a triangle surface: the per-vertex scalar a registration on the sphere can
// match when no FreeSurfer curvature or sulcal depth is at hand (vpm/surface_registration.hpp).
#include <Eigen/Core>

#include "vpm/mesh.hpp"

namespace vpm {

/// Signed mean curvature at each vertex of a closed or open oriented surface: half the cotangent
/// Laplacian of the position along the vertex normal, (1/2) (L x)_i . n_i / A_i, with A_i a third
/// of the areas of the vertex's faces and n_i the area-weighted normal of its faces. Positive where
/// the surface bends away from its normals (a gyrus's crown on an outward-oriented brain), in
/// inverse length units. Summed with the areas A_i over a region it is the region's integral of
/// the mean curvature, the same for any fine triangulation of the same shape (this is what makes
/// two subjects' curvatures comparable after smoothing). Vertices in no face get 0.
Eigen::VectorXd mean_curvature(const TriSurface& surface);

}  // namespace vpm
