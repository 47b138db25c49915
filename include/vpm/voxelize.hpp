#pragma once
// A closed triangle surface turned into a binary image of the solid it encloses (the way to mesh
// a surface whose triangles cross each other: mesh_image then meshes the mask).
#include "vpm/image.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// Rasterises the solid enclosed by the closed surface s on a grid of cubic voxels of
/// `voxel_mm` (the surface's units) covering its bounding box plus `pad_voxels` on every side:
/// value 1 where the winding number of s about the voxel centre is non-zero, 0 elsewhere
/// (counted along each grid column from the signed crossings of the column with the
/// triangles, so parts that overlap or pass through each other are a union, and the
/// orientation of s does not matter). The affine maps voxel (i, j, k) to the box corner plus
/// voxel_mm (i, j, k); `path` is left empty. InputError when voxel_mm <= 0, the surface is
/// empty, or the grid would exceed 512^3 voxels.
Image voxelize_surface(const TriSurface& s, double voxel_mm, int pad_voxels = 4);

}  // namespace vpm
