#pragma once
// A patient's per-element result mapped back to the patient's own native space (paper 6.2,
// Fig. 10): through the patient's registered ball mesh, whose vertices sit in the common ball
// and whose point field `original_position` holds their native positions.
#include <vector>

#include "vpm/elements.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// The patient's native mesh (vertices = original_position of `registered`) with the per-element
/// `values` (one per element, e.g. z) as fields: point field `name` at each vertex's ball
/// position, cell field `name` at each tet's ball centroid. InputError when `registered` has no
/// original_position field.
TetMesh native_mesh_with_values(const TetMesh& registered, const CanonicalElements& elements,
                                const std::vector<std::vector<double>>& values, const std::vector<std::string>& names);

/// Per-element `values` pushed onto the voxel grid of `grid` (same dims and affine): each voxel
/// centre is located in the native mesh, carried into the ball by the same barycentric
/// combination of the ball vertices, and takes the value of the element there; voxels outside
/// the native mesh get `outside`. Runs on the host threads.
Image native_volume(const TetMesh& registered, const CanonicalElements& elements, const std::vector<double>& values,
                    const Image& grid, float outside = 0.0f);

}  // namespace vpm
