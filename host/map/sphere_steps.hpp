#pragma once
// Private: the numerical steps of the boundary-to-sphere map (map/sphere_map.cpp): a surface
// cotangent Laplacian and Dirichlet solve for the planar conformal map, stereographic
// projection, the south-pole correction, Moebius balancing and the area-equalising flow.
// The surface Laplacian here is of a triangle surface (2-D cotangents); the linalg layer's is
// of tet meshes.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <string>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

using SpMat = Eigen::SparseMatrix<double>;

/// Cotangent weights w_ij = (cot a + cot b)/2 of a triangle surface as a Laplacian L
/// (L_ii = sum_j w_ij, L_ij = -w_ij), k x k. `clamp` > 0 replaces weights below clamp * mean.
SpMat cot_laplacian(const Points& p, const Triangles& f, double clamp);

/// The system of A's free rows and columns (those not in `fixed`): idx maps a vertex to its
/// free row (-1 when fixed), rhs = source_F - A_FB u_B (source: null for none).
struct FreeRows {
  std::vector<int> idx;
  SpMat a;
  Eigen::MatrixXd rhs;
};
FreeRows free_rows(const SpMat& A, const std::vector<char>& fixed, const Eigen::MatrixXd& u,
                   const Eigen::MatrixXd* source = nullptr);

/// Solves A_FF u_F = -A_FB u_B for the columns of u (k x c), rows with fixed[i] given, by sparse
/// Cholesky (iterative = false) or Jacobi CG to relative residual `tol` (warm start from u).
/// Returns false if the solve failed or the result is not finite.
bool dirichlet_solve(const SpMat& A, const std::vector<char>& fixed, Eigen::MatrixXd& u, bool iterative = false,
                     double tol = 1e-10, int* iterations = nullptr);

/// Inverse stereographic projection of plane points z (k x 2) to the unit sphere, the plane's
/// origin going to the south pole.
Points inverse_stereo_north(const Eigen::MatrixXd& z);

/// Scales every row of s to unit length.
void normalize_rows(Points& s);

/// South-pole correction (Choi, Lam & Lui 2015): composes s with the quasi-conformal map whose
/// Beltrami coefficient cancels the distortion near the north pole. False when it failed.
bool south_pole_correction(const Points& in, const Triangles& f, Points& s);

/// Moves the w-weighted centroid of the sphere points s to the origin by Moebius maps of the
/// ball; returns the iterations, *final_norm the centroid's norm reached.
int moebius_balance(const Eigen::VectorXd& w, Points& s, int max_it, double tol, double* final_norm);

/// Area-equalising flow on the sphere (see map/sphere_steps.cpp); returns the steps taken.
int area_flow(const Points& in, const Triangles& f, Points& s, int steps, bool until_unflipped);

/// What equalise_density did. misfit_* = area-weighted mean square of log(sphere area /
/// target) over the vertices (0 when every vertex has its target); distortion_* =
/// area_distortion (against the input's triangle areas).
struct EquiarealStats {
  int steps = 0, flips_before = 0;
  double misfit_before = 0, misfit_after = 0, distortion_before = 0, distortion_after = 0;
  std::string solver;  ///< what solved the last step's Laplacian system (DensitySolver::name)
  double solve_seconds = 0;  ///< wall-clock seconds in the steps' Laplacian solves
};
/// Moves the sphere map s of surface (in, f) until each vertex's lumped sphere area (a third of
/// its triangles' chord areas) is its share `target` (k entries, normalised here) of the
/// sphere's, by a log-density Moser flow on the sphere (map/sphere_density.cpp). Never flips
/// a triangle that was not flipped; stops after `max_steps`, when the area distortion is at
/// most `tolerance`, or when it stalls. `device`: where the steps' Laplacian systems are solved
/// (null: the host; map/density_solve.hpp).
EquiarealStats equalise_density(const Points& in, const Triangles& f, const Eigen::VectorXd& target, Points& s,
                                int max_steps, double tolerance, Device* device = nullptr);
/// What progressive_sphere did.
struct ProgressiveStats {
  int passes = 0, collapses = 0, sweeps = 0;
  double seconds = 0;
};
/// A sphere embedding (k x 3, unit rows) of the closed genus-0 surface (in, f) over all k
/// vertices, f outward, with every chord triangle facing outwards (map/sphere_progressive.cpp):
/// half-edge collapses (link condition; independent sets, shortest input edge first) down to a
/// tetrahedron, which goes on a regular tetrahedron of the sphere; then the collapses undone in
/// reverse, each restored vertex put next to its partner inside the kernel of its ring, and
/// the vertices relaxed toward their neighbours' centroid by moves that keep every triangle
/// valid (2 sweeps a level, 10 at the end). No precision loss can fold it, unlike the conformal
/// map of a long tube. InputError if f is not a closed genus-0 triangulation of k vertices;
/// NumericalError if no valid position exists (not seen).
Points progressive_sphere(const Points& in, const Triangles& f, ProgressiveStats* stats = nullptr);

/// What axial_sphere did: the poles (the input's vertices on the north and south poles).
struct AxialStats {
  int north = -1, south = -1;
  double seconds = 0;
};
/// A sphere map (k x 3, unit rows) of the closed genus-0 surface (in, f), f outward, as a
/// cylinder between the two vertices farthest apart along the edges (map/sphere_axial.cpp): the
/// height a harmonic function between the poles, the angle the harmonic one-form of period one
/// around them, the latitude set so that each band between two heights has its share of the
/// area. For tubes and elongated shapes, whose conformal map underflows. The caller checks the
/// chord triangles' orientation; empty when the solves failed or the poles' rings touch.
Points axial_sphere(const Points& in, const Triangles& f, AxialStats* stats = nullptr);

/// Each vertex's share of the surface's area (a third of its triangles' areas), summing to 1.
Eigen::VectorXd vertex_area_shares(const Points& in, const Triangles& f);

}  // namespace vpm::detail
