#pragma once
// The fine steps of dense registration (DenseRegistrationOptions::fine_iterations): a
// displacement represented on the subject's mesh itself, one vector per vertex, so the step
// resolves what the mesh resolves instead of what a Gaussian field's finest width does.
//
// At each vertex, the image force's local least-squares system (Lucas-Kanade: a = sum w g g^T,
// b = sum w g (S - T) over the image grid points within 3 sigma) asks for a displacement; the
// displacement field minimises
//     sum_v (u_v^T a_v u_v - 2 u_v^T b_v) + smoothness x sum_edges |u_i - u_j|^2
// (a Gauss-Newton step of the image mismatch with a membrane regulariser on the mesh's edges),
// with the a_v scaled to a mean trace of 3 and, at surface vertices, the normal component held
// at zero (the sphere stays the domain). The step is not volume-preserving by itself: the
// caller restores the volumes after it (a projection onto volume preservation), the nonlinear
// counterpart of a Leray projection.
#include <vector>

#include <Eigen/Core>

#include "vpm/mesh.hpp"
#include "vpm/rbf.hpp"

namespace vpm {

/// The mesh displacement (n x 3) that best satisfies `local` (one system per vertex, e.g.
/// ImageForce::local_systems at the vertices) under the membrane penalty `smoothness` over the
/// edges of `tets`; vertices with `boundary` set move only tangentially to the unit sphere
/// (their position is on it). Each displacement is capped at `cap` in length. Solved by
/// conjugate gradients on the host (Jacobi preconditioner, relative residual 1e-6).
Points fine_displacement(const LocalSystems& local, const Points& ball, const Tets& tets,
                         const std::vector<char>& boundary, double smoothness, double cap);

}  // namespace vpm
