#pragma once
// Private: the dense iterations of a registration in the unit disk (vpm/surface_registration.hpp,
// register_in_disk with a template), between the landmark flow and the restoration: the sphere's
// steps a-d in the plane, the scalars smoothed on a square grid, the field's centres on a
// triangular lattice, each step's field the disk's stream-function field (disk_field.hpp).
#include <Eigen/Core>
#include <vector>

#include "map/surface_polish.hpp"
#include "vpm/surface_registration.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// Moves the subject's vertices `x` (in the disk, in place; domain.boundary's on the circle) so
/// that its per-vertex scalar `values` matches `templ`'s; `carried` (the landmarks' images) moves
/// with them. `reference` is the subject's input disk (where its area shares are taken; its scalar
/// is smoothed where the vertices are when each level starts); no step adds a flipped face. Without landmarks, a rotation about the centre
/// is searched first (options.rotation_search). The advections run on `device` (advect_in_disk),
/// the rest on the host threads.
SphereMatchReport match_in_disk(Device& device, std::vector<Eigen::Vector2d>& x, std::vector<Eigen::Vector2d>& carried,
                                const Points& reference, const Triangles& faces, const Eigen::VectorXd& values,
                                const DiskTemplate& templ, const SphereMatchOptions& options,
                                const SurfaceDomainMoves& domain);

}  // namespace vpm::detail
