#pragma once
// The steps of register_landmarks (registration.cpp), one file each in host/register.
#include <Eigen/Core>
#include <vector>

#include "vpm/registration.hpp"
#include "vpm/polish.hpp"

namespace vpm {

/// Refuses invalid input (RegistrationInputError); returns the rows of the landmarks to fit,
/// duplicates (same landmark, same target) dropped. `boundary` marks the boundary vertices.
std::vector<Eigen::Index> check_registration_input(const Points& ball, const std::vector<char>& boundary,
                                                   const Points& landmarks, const Points& targets,
                                                   const RegistrationOptions& options);

/// The angle of a rotation in degrees.
double rotation_degrees(const Eigen::Matrix3d& rotation);

/// The Gaussian width: lambda, the landmark spacing it was derived from and the leave-one-out
/// candidates (when RegistrationOptions::width_loo chose it). `p` (rotated), `q`: the landmarks.
struct RegistrationWidth {
  double lambda = 0;
  double spacing = 0;
  std::vector<WidthLooCandidate> loo;
};
RegistrationWidth choose_width(const Points& p, const Points& q, const RegistrationOptions& options);

/// Landmark errors of `result.landmarks_final` against `targets`, and the boundary drift of
/// `after` (boundary vertices put back on the sphere when options.project_boundary).
void measure_flow(RegistrationResult& result, Points& after, const std::vector<char>& boundary,
                  const Points& targets, const RegistrationOptions& options);

/// max |u . n| at `samples` sphere points over about ten of `fields`, the last one included.
double max_normal_velocity(Device& device, const std::vector<DivFreeField>& fields, int samples);

/// Vertices of `before` that sit at a landmark (never moved after the flow).
std::vector<char> landmark_vertices(const Points& before, const Points& landmarks);

/// Untangles the tets the flow inverted (`v0`: volumes before, `v1`: after, updated) with the
/// boundary and landmark vertices fixed; nullopt when there were none.
std::optional<RegistrationUntangle> untangle_flow_folds(Device& device, const Points& before,
                                                        const Tets& tets, Points& after,
                                                        const std::vector<char>& fixed,
                                                        const Eigen::VectorXd& v0, Eigen::VectorXd& v1,
                                                        int rings);

/// The mesh a volume restoration works on: the positions whose tet volumes it restores
/// (`before`, the ball before the flow), the tets, and their topology, built once per mesh by
/// the caller and used by every restoration of a registration.
struct RestoreMesh {
  const Points& before;
  const Tets& tets;
  const TetTopology& topology;
};

/// Gives back the volume lost under the flow (RegistrationOptions::restore_volumes), with the
/// landmark vertices pinned and each moved landmark held in place (an anchor of the polish, or
/// its tet's vertices pinned where the tet touches the boundary); `holds` (VolumeHold) keep
/// points from sliding across image edges (dense registration with an image force). The polish
/// runs opt.restore_iterations CGLS iterations a step, at most opt.restore_rounds steps, its
/// directions where opt.restore_polish asks (vpm/placement.hpp).
RegistrationRestore restore_volumes(Device& device, const RestoreMesh& mesh, Points& after,
                                    const std::vector<char>& landmark_vertex, const Points& landmarks_final,
                                    const std::vector<VolumeHold>& holds, const RegistrationOptions& opt);

}  // namespace vpm
