#pragma once
// Divergence-free interpolation of velocity samples with matrix-valued Gaussian radial basis
// functions (Hu, Zou & Hua 2014, section 5.3, after Narcowich & Ward / Lowitzsch).
//
// Scalar Gaussian psi(r) = exp(-lambda |r|^2), width 1/sqrt(lambda) (ball units).
//
// * Free kernel (paper eq. 22-28): Phi(r) = (grad grad^T - Laplacian I) psi(r)
//     = [(4 lambda - 4 lambda^2 |r|^2) I + 4 lambda^2 r r^T] exp(-lambda |r|^2),  Phi(0) = 4 lambda I.
//   Every column is exactly divergence-free (div of column k = d_k Lap psi - d_k Lap psi = 0).
// * Tangent kernel (this project's option, exact boundary condition): with phi(x) = 1 - |x|^2,
//     K(x, y) = curl_x curl_y^T [phi(x) phi(y) psi(x - y)],
//   i.e. K_mi = delta_mi tr(H) - H_im with H_nk = d/dx_n d/dy_k [phi(x) phi(y) psi(x - y)].
//   Each column is the curl of phi(x) W(x), so it is divergence-free, and on the unit sphere
//   (phi = 0) it reduces to grad(phi) x W = -2 x cross W: tangent to the sphere by construction.
//   With phi = 1 it is exactly the free kernel. K is symmetric positive (semi)definite.
//
// A field u(x) = sum_j K(x, c_j) a_j is fitted to samples (x_i, v_i) by solving the 3N x 3N
// symmetric positive definite Gram system on the host in double precision (Eigen LLT).
// With the free kernel, optional boundary samples s_j on the unit sphere add the constraints
// u(s_j) . s_j = 0 (paper eq. 29's boundary-correction field, solved jointly so the velocity
// samples stay interpolated exactly); their centres carry coefficients beta_j s_j.
#include <Eigen/Core>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

class Device;

enum class RbfKernel {
  Free,     ///< Phi = (grad grad^T - Lap I) psi: divergence-free, no boundary condition
  Tangent,  ///< curl curl^T [phi(x) phi(y) psi]: divergence-free and tangent to the unit sphere
};

/// The free kernel matrix Phi(r) (3 x 3, symmetric) for the offset r = x - y.
Eigen::Matrix3d divfree_kernel(const Eigen::Vector3d& r, double lambda);
/// The tangent kernel matrix K(x, y) (3 x 3; K(x, y) = K(y, x)^T).
Eigen::Matrix3d tangent_kernel(const Eigen::Vector3d& x, const Eigen::Vector3d& y, double lambda);

/// A fitted divergence-free field u(x) = sum_j K(x, centres_j) coefficients_j.
struct DivFreeField {
  RbfKernel kernel = RbfKernel::Free;
  double lambda = 1;    ///< Gaussian parameter (1 / width^2), 1 / ball units^2
  Points centres;       ///< c x 3 (ball coordinates)
  Points coefficients;  ///< c x 3

  /// u(x) for one point (host).
  Eigen::Vector3d operator()(const Eigen::Vector3d& x) const;
};

/// u at each row of `points` (n x 3) on the host (reference). n x 3.
Points evaluate(const DivFreeField& field, const Points& points);
/// Same on `device`: kernel `register.eval_field`, one work item per point looping over the
/// centres (host device: the reference above).
Points evaluate(Device& device, const DivFreeField& field, const Points& points);

struct RbfFitOptions {
  RbfKernel kernel = RbfKernel::Free;
  double lambda = 1;  ///< Gaussian parameter, > 0
  /// Free kernel only: points on the unit sphere (b x 3, unit length) where u . n = 0 is imposed.
  Points boundary_samples;
  /// Samples closer than this (ball units) are merged into one (mean position and velocity).
  double merge_distance = 1e-9;
  /// Smoothing: ridge x the mean diagonal of the sample Gram matrix is added to its diagonal, so
  /// the field approximates the samples instead of interpolating them (0: interpolation).
  /// Large ridge systems (over 400 samples, no boundary samples) are solved by Jacobi-
  /// preconditioned conjugate gradients (relative residual 1e-12) instead of Cholesky, with a
  /// sparse Gram matrix that leaves out the pairs farther apart than 5 widths (psi < 1.4e-11;
  /// the dense one when estimate_condition is set).
  double ridge = 0;
  /// Estimate the 2-norm condition number of the Gram matrix (eigenvalues: O(N^3), for reports).
  bool estimate_condition = false;
  /// fit_divfree_weighted only: the relative residual (in the K norm) its conjugate gradients
  /// stop at, in (0, 1).
  double tolerance = 1e-10;
};

struct RbfFitInfo {
  int samples = 0;            ///< velocity samples after merging
  int merged = 0;             ///< samples removed by merging
  int boundary_constraints = 0;
  double condition = 0;       ///< 2-norm condition number when estimated, else 0
  bool regularised = false;   ///< LLT failed; a ridge of 1e-12 * mean diagonal was added
  double max_residual = 0;    ///< max |u(x_i) - v_i| over the (merged) samples
};

/// Fits the field to velocity samples `points` (N x 3) -> `velocities` (N x 3).
/// Throws NumericalError when the Gram matrix cannot be factorised even with the ridge.
DivFreeField fit_divfree(const Points& points, const Points& velocities,
                         const RbfFitOptions& options, RbfFitInfo* info = nullptr);

/// Local least-squares data at the centres of a field: u(c_j) should minimise
/// u^T a_j u - 2 u^T b_j (a_j symmetric positive semidefinite 3 x 3, b_j a 3-vector): a_j says
/// how firmly and in which directions the data constrain the field there (an image edge constrains
/// only the component across it, a flat region nothing).
struct LocalSystems {
  std::vector<Eigen::Matrix3d> a;
  Points b;  ///< c x 3
};

/// The field with centres `centres` (c x 3) that best satisfies `local` (one system per centre)
/// under a smoothness penalty: it minimises sum_j (u_j^T a_j u_j - 2 u_j^T b_j) + mu a^T K a
/// (u_j = u(c_j), K the Gram matrix of the centres, a the coefficients: the field's RKHS norm),
/// mu = options.ridge x the mean Gram diagonal x the mean trace(a_j) / 3. Where a_j = alpha I
/// for every centre this is fit_divfree with the same ridge to the samples b_j / alpha; where the
/// data constrain a direction weakly or not at all, the field there follows from its neighbours
/// (and, being divergence-free, from what moves around it) instead of being pulled to zero.
/// Solves (A K + mu I) a = b by conjugate gradients in the K inner product (self-adjoint there),
/// with the sparse Gram matrix of fit_divfree (pairs beyond 5 widths left out), to the relative
/// residual options.tolerance. options.kernel and lambda are used; boundary samples are not
/// supported (InputError), nor a ridge <= 0 or a tolerance outside (0, 1).
DivFreeField fit_divfree_weighted(const Points& centres, const LocalSystems& local, const RbfFitOptions& options,
                                  RbfFitInfo* info = nullptr);

/// Leave-one-out errors |u_{-j}(x_j) - v_j| of the interpolant without boundary samples, from
/// one inverse: e_j = (block j of A^-1)^-1 (A^-1 v)_j. Length N.
Eigen::VectorXd loo_errors(const Points& points, const Points& velocities, RbfKernel kernel,
                           double lambda);

/// Mean distance of each point to its nearest other point (0 for fewer than two points).
double mean_nearest_spacing(const Points& points);

/// `n` nearly uniform points on the unit sphere (Fibonacci spiral), n x 3.
Points fibonacci_sphere(int n);

}  // namespace vpm
