#pragma once
// Private: the polish of a surface map's face areas (vpm/surface_map.hpp step 2), for the sphere
// and the disk: Gauss-Newton steps on the face areas against the input's, over the moves the
// domain allows, each step put back on the domain, fold-checked and line-searched.
#include <Eigen/Core>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/surface_map.hpp"

namespace vpm::detail {

/// What moves the domain allows and how points go back onto it. sphere: moves tangent to the
/// sphere, every point normalised. disk: moves in the plane z = 0, the `boundary` vertices' along
/// the unit circle (and normalised onto it).
struct SurfaceDomainMoves {
  SurfaceDomain domain = SurfaceDomain::sphere;
  std::vector<char> boundary;  ///< disk: 1 on the boundary loop's vertices (n entries)
  std::vector<char> fixed;     ///< 1 on vertices held still (n entries, or empty: none)
  /// u projected on the moves allowed at vertex v (at x).
  Eigen::Vector3d project(const Points& x, int v, const Eigen::Vector3d& u) const;
  /// x put back on the domain.
  Points place(const Points& x) const;
  /// The faces flipped at x (flipped_faces_in).
  std::vector<int> flipped(const Points& x, const Triangles& f) const;
};

/// Polishes x (a fold-free map of the faces `f` onto the domain) towards the face areas `area0`
/// (the input's), steps and stopping rule of SurfaceMapOptions; fills rep.polish,
/// rep.stop_reason and rep.seconds_polish.
void polish_surface(const SurfaceDomainMoves& domain, const Triangles& f, const Eigen::VectorXd& area0,
                    const SurfaceMapOptions& opt, Points& x, SurfaceMapReport& rep);

}  // namespace vpm::detail
