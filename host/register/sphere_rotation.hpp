#pragma once
// Private: the rotation search that starts a dense registration without landmarks
// (sphere_match.cpp). A sphere map is unique only up to a rotation, so two subjects' maps may
// differ by one; the dense steps follow a scalar's local mismatch and do not undo a rotation from
// far. The search finds the rotation R that best correlates the subject's smoothed scalar f with
// the template's g (g(R x) against f(x) at evenly spread directions): a grid of rotations, then a
// pattern search from the best few; maps whose scalars already correlate well are not searched.
#include <Eigen/Core>

#include "vpm/locate.hpp"
#include "vpm/mesh.hpp"

namespace vpm::detail {

struct RotationFound {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  double correlation_identity = 0;  ///< of the smoothed scalars with no rotation
  double correlation = 0;           ///< at `rotation`
};

/// The rotation of the subject's sphere `x` (faces `faces`, smoothed scalar `f` at its vertices)
/// that best matches the template's smoothed scalar `g` at the vertices of `templ` (its locator);
/// the identity when the scalars correlate at least 0.75 without a rotation.
RotationFound search_rotation(const Points& x, const Triangles& faces, const Eigen::VectorXd& f, const SphereLocator& templ,
                              const Eigen::VectorXd& g);

}  // namespace vpm::detail
