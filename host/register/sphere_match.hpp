#pragma once
// Private: the dense iterations of a registration on the sphere (vpm/surface_registration.hpp,
// steps a-d), between the landmark flow and the restoration.
#include <Eigen/Core>
#include <vector>

#include "map/surface_polish.hpp"
#include "vpm/surface_registration.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// Moves the subject's vertices `x` (on the sphere, in place) so that its per-vertex scalar
/// `values` matches `templ`'s; `carried` (the landmarks' images) moves with them. `reference` is
/// the subject's input sphere (where its scalar is smoothed and its area shares are taken);
/// `domain` says which faces may not flip (domain.fixed is not used: every vertex moves). The
/// advections run on `device` (advect_on_sphere), the rest on the host threads.
SphereMatchReport match_on_sphere(Device& device, std::vector<Eigen::Vector3d>& x, std::vector<Eigen::Vector3d>& carried,
                                  const Points& reference, const Triangles& faces, const Eigen::VectorXd& values,
                                  const SphereTemplate& templ, const SphereMatchOptions& options,
                                  const SurfaceDomainMoves& domain);

}  // namespace vpm::detail
