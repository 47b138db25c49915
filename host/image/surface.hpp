#pragma once
// Surfaces of the image layer: marching tetrahedra on a grid, surface measures and the
// closed genus-0 check used before and after remeshing.
#include <string>
#include <vector>

#include "image/mask_grid.hpp"
#include "vpm/mesh.hpp"
#include "vpm/mesh_image_report.hpp"

namespace vpm::detail {

/// Extracts the level set f = iso of the piecewise-linear interpolation of `f` on the Kuhn
/// split of the grid cells. Vertices in grid index coordinates; triangles oriented with
/// normals pointing from f > iso to f < iso. No grid value may equal iso.
TriSurface marching_tets(const Grid3& g, const std::vector<float>& f, float iso);

/// Mean edge length (each triangle's three edges; shared edges count twice).
double mean_edge(const TriSurface& s);

/// Signed volume enclosed by a closed surface (positive for outward normals).
double enclosed_volume(const TriSurface& s);

/// Size, Euler characteristic, mean edge and angle range of `s`.
SurfaceStats surface_stats(const TriSurface& s);

/// Throws InputError "<source>: <what> is not a closed genus-0 surface: <why>" when `s` has
/// open or non-manifold edges, non-manifold vertices, several components or a handle.
void check_closed_genus0(const TriSurface& s, const std::string& source, const std::string& what);

}  // namespace vpm::detail
