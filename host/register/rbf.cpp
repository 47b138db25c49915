#include "vpm/rbf.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Sparse>
#include <boost/compute/container/vector.hpp>
#include <cmath>
#include <limits>
#include <sstream>

#include "register/rbf_gram.hpp"
#include "core/device_cl.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace detail {
// the kernels applied to a coefficient, shared with kernels/register.cl
#include "kernels/rbf_kernel.clh"
}  // namespace detail

namespace bc = boost::compute;

Eigen::Matrix3d divfree_kernel(const Eigen::Vector3d& r, double lambda) {
  const double r2 = r.squaredNorm();
  const double psi = std::exp(-lambda * r2);
  Eigen::Matrix3d k = (4 * lambda * lambda * psi) * (r * r.transpose());
  k.diagonal().array() += (4 * lambda - 4 * lambda * lambda * r2) * psi;
  return k;
}

Eigen::Matrix3d tangent_kernel(const Eigen::Vector3d& x, const Eigen::Vector3d& y, double lambda) {
  const Eigen::Vector3d r = x - y;
  const double psi = std::exp(-lambda * r.squaredNorm());
  const double px = 1 - x.squaredNorm(), py = 1 - y.squaredNorm();
  // H_nk = d/dx_n d/dy_k [phi(x) phi(y) psi(x - y)] / psi
  Eigen::Matrix3d h = 4 * x * y.transpose() - 4 * lambda * py * x * r.transpose() +
                      4 * lambda * px * r * y.transpose() -
                      px * py * 4 * lambda * lambda * r * r.transpose();
  h.diagonal().array() += px * py * 2 * lambda;
  Eigen::Matrix3d k = -h.transpose();
  k.diagonal().array() += h.trace();
  return psi * k;
}

namespace {

// Gram matrix of point samples only (3N x 3N).
Eigen::MatrixXd gram(const Points& p, RbfKernel kind, double lambda) {
  const Eigen::Index n = p.rows();
  Eigen::MatrixXd a(3 * n, 3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j <= i; ++j) {
      const Eigen::Matrix3d k = kernel_block(kind, p.row(i).transpose(), p.row(j).transpose(), lambda);
      a.block<3, 3>(3 * i, 3 * j) = k;
      a.block<3, 3>(3 * j, 3 * i) = k.transpose();
    }
  return a;
}

}  // namespace

Eigen::Vector3d DivFreeField::operator()(const Eigen::Vector3d& x) const {
  double u[3] = {0, 0, 0};
  const double p[3] = {x(0), x(1), x(2)};
  for (Eigen::Index j = 0; j < centres.rows(); ++j) {
    const double c[3] = {centres(j, 0), centres(j, 1), centres(j, 2)};
    const double a[3] = {coefficients(j, 0), coefficients(j, 1), coefficients(j, 2)};
    double t[3];
    if (kernel == RbfKernel::Free) {
      const double r[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
      detail::rk_free(r, a, lambda, t);
    } else {
      detail::rk_tangent(p, c, a, lambda, t);
    }
    for (int k = 0; k < 3; ++k) u[k] += t[k];
  }
  return Eigen::Vector3d(u[0], u[1], u[2]);
}

Points evaluate(const DivFreeField& field, const Points& points) {
  Points out(points.rows(), 3);
  for (Eigen::Index i = 0; i < points.rows(); ++i)
    out.row(i) = field(points.row(i).transpose()).transpose();
  return out;
}

Points evaluate(Device& dev, const DivFreeField& field, const Points& points) {
  if (dev.is_host() || points.rows() == 0) return evaluate(field, points);
  auto& q = dev.cl().queue;
  const Eigen::Index nc = field.centres.rows();
  // Empty buffers are not allowed: pad with one zero centre.
  Points c = nc ? field.centres : Points::Zero(1, 3);
  Points a = nc ? field.coefficients : Points::Zero(1, 3);
  bc::vector<double> dx(points.data(), points.data() + points.size(), q);
  bc::vector<double> dc(c.data(), c.data() + c.size(), q);
  bc::vector<double> da(a.data(), a.data() + a.size(), q);
  bc::vector<double> du(static_cast<size_t>(points.size()), dev.cl().context);
  auto k = dev.cl().kernel("register", "eval_field");
  k.set_args(static_cast<int>(points.rows()), dx, static_cast<int>(nc), dc, da, field.lambda,
             field.kernel == RbfKernel::Tangent ? 1 : 0, du);
  dev.cl().launch(k, static_cast<size_t>(points.rows()));
  Points out(points.rows(), 3);
  bc::copy(du.begin(), du.end(), out.data(), q);
  return out;
}

namespace {

/// Merges near-duplicate samples (greedy clusters around the first unassigned sample) into
/// `p`, `v`: each cluster's mean point and mean velocity.
void merge_samples(const Points& points_in, const Points& velocities_in, double merge_distance, Points& p,
                   Points& v) {
  const Eigen::Index n0 = points_in.rows();
  std::vector<int> cluster(static_cast<size_t>(n0), -1);
  p.resize(n0, 3);
  v.resize(n0, 3);
  int nc = 0;
  for (Eigen::Index i = 0; i < n0; ++i) {
    if (cluster[static_cast<size_t>(i)] >= 0) continue;
    p.row(nc).setZero();
    v.row(nc).setZero();
    int members = 0;
    for (Eigen::Index j = i; j < n0; ++j) {
      if (cluster[static_cast<size_t>(j)] >= 0) continue;
      if (j != i && (points_in.row(j) - points_in.row(i)).norm() > merge_distance) continue;
      cluster[static_cast<size_t>(j)] = nc;
      p.row(nc) += points_in.row(j);
      v.row(nc) += velocities_in.row(j);
      ++members;
    }
    p.row(nc) /= members;
    v.row(nc) /= members;
    ++nc;
  }
  p.conservativeResize(nc, 3);
  v.conservativeResize(nc, 3);
}

/// The blocks of the normal-cancelling constraints at sphere points `s` (eq. 29) in the
/// system matrix `a`, whose first 3 x p.rows() rows and columns hold the sample Gram matrix.
void add_boundary_constraints(Eigen::MatrixXd& a, const Points& p, const Points& s, double lambda) {
  const Eigen::Index nc = p.rows();
  for (Eigen::Index j = 0; j < s.rows(); ++j) {
    const Eigen::Vector3d sj = s.row(j).transpose(), nj = sj.normalized();
    for (Eigen::Index i = 0; i < nc; ++i) {
      const Eigen::Vector3d col = divfree_kernel(p.row(i).transpose() - sj, lambda) * nj;
      a.block<3, 1>(3 * i, 3 * nc + j) = col;
      a.block<1, 3>(3 * nc + j, 3 * i) = col.transpose();
    }
    for (Eigen::Index k = 0; k <= j; ++k) {
      const Eigen::Vector3d sk = s.row(k).transpose(), nk = sk.normalized();
      const double e = nj.dot(divfree_kernel(sj - sk, lambda) * nk);
      a(3 * nc + j, 3 * nc + k) = e;
      a(3 * nc + k, 3 * nc + j) = e;
    }
  }
}

/// Solves the symmetric positive definite system a x = rhs by Cholesky, with a small ridge
/// when that fails (then `regularised`); NumericalError when even that fails.
Eigen::VectorXd solve_gram(Eigen::MatrixXd& a, const Eigen::VectorXd& rhs, double lambda, Eigen::Index samples,
                           bool& regularised) {
  const Eigen::Index dim = a.rows();
  Eigen::LLT<Eigen::MatrixXd> llt(a);
  if (llt.info() != Eigen::Success) {
    const double ridge = 1e-12 * a.diagonal().mean();
    a.diagonal().array() += ridge;
    llt.compute(a);
    regularised = true;
    if (llt.info() != Eigen::Success) {
      std::ostringstream msg;
      msg << "divergence-free interpolation: the " << dim << " x " << dim
          << " Gram matrix is not positive definite even with a ridge (lambda " << lambda << ", " << samples
          << " samples): samples too close for this width";
      throw NumericalError(msg.str());
    }
  }
  return llt.solve(rhs);
}

/// Jacobi-preconditioned conjugate gradients for a symmetric positive definite system given by
/// its product `apply(d)` and inverse diagonal; relative residual 1e-12.
template <class Apply>
Eigen::VectorXd jacobi_cg(const Apply& apply, const Eigen::VectorXd& inv_diag, const Eigen::VectorXd& rhs) {
  Eigen::VectorXd x = Eigen::VectorXd::Zero(rhs.size()), r = rhs, z = inv_diag.cwiseProduct(r), d = z;
  double rz = r.dot(z);
  const double stop = 1e-24 * rhs.squaredNorm();
  for (Eigen::Index it = 0; it < 10 * rhs.size() && r.squaredNorm() > stop; ++it) {
    const Eigen::VectorXd ad = apply(d);
    const double alpha = rz / d.dot(ad);
    x += alpha * d;
    r -= alpha * ad;
    z = inv_diag.cwiseProduct(r);
    const double rz_next = r.dot(z);
    d = z + (rz_next / rz) * d;
    rz = rz_next;
  }
  return x;
}

/// The ridge-regularised Gram system (smoothing fits) by Jacobi CG: the ridge bounds the
/// condition number, so a few dozen products replace the O(n^3) Cholesky factorisation.
Eigen::VectorXd solve_ridge_cg(const Eigen::MatrixXd& a, const Eigen::VectorXd& rhs) {
  return jacobi_cg([&](const Eigen::VectorXd& d) { return Eigen::VectorXd(a.selfadjointView<Eigen::Lower>() * d); },
                   a.diagonal().cwiseInverse(), rhs);
}

/// The ridge-regularised Gram system of many samples, sparse (rbf_gram.hpp), by Jacobi CG. For
/// fits with thousands of centres, whose dense Gram matrix would not fit in memory.
Eigen::VectorXd solve_ridge_sparse(const Points& p, RbfKernel kind, double lambda, double ridge,
                                   const Eigen::VectorXd& rhs, double& max_residual) {
  const Eigen::Index n = p.rows();
  const SparseGram a = sparse_gram(p, kind, lambda);
  const double shift = ridge * a.diagonal().mean();
  const Eigen::VectorXd x = jacobi_cg([&](const Eigen::VectorXd& d) { return Eigen::VectorXd(multiply(a, d) + shift * d); },
                                      (a.diagonal().array() + shift).inverse().matrix(), rhs);
  const Eigen::VectorXd u = a * x - rhs;  // the field at the samples minus the samples
  max_residual = 0;
  for (Eigen::Index i = 0; i < n; ++i) max_residual = std::max(max_residual, u.segment<3>(3 * i).norm());
  return x;
}

/// Ridge systems larger than this (3 x samples) go to the sparse solver: at the dense
/// registration's finest level (1,551 centres) it cut the fit from 1.0-1.6 s to 0.2-0.3 s with
/// the same demo result to 3 decimals.
constexpr Eigen::Index kSparseFitSize = 1200;

DivFreeField fit_sparse(const Points& p, const Points& v, const RbfFitOptions& opt, int merged, RbfFitInfo* info) {
  const Eigen::Index nc = p.rows();
  Eigen::VectorXd rhs(3 * nc);
  for (Eigen::Index i = 0; i < nc; ++i) rhs.segment<3>(3 * i) = v.row(i).transpose();
  double max_residual = 0;
  const Eigen::VectorXd sol = solve_ridge_sparse(p, opt.kernel, opt.lambda, opt.ridge, rhs, max_residual);
  DivFreeField f;
  f.kernel = opt.kernel;
  f.lambda = opt.lambda;
  f.centres = p;
  f.coefficients.resize(nc, 3);
  for (Eigen::Index i = 0; i < nc; ++i) f.coefficients.row(i) = sol.segment<3>(3 * i).transpose();
  if (info) {
    *info = RbfFitInfo{};
    info->samples = static_cast<int>(nc);
    info->merged = merged;
    info->max_residual = max_residual;
  }
  return f;
}

}  // namespace

DivFreeField fit_divfree(const Points& points_in, const Points& velocities_in,
                         const RbfFitOptions& opt, RbfFitInfo* info) {
  if (points_in.rows() != velocities_in.rows())
    throw InputError("fit_divfree: " + std::to_string(points_in.rows()) + " points but " +
                     std::to_string(velocities_in.rows()) + " velocities");
  if (!(opt.lambda > 0)) throw InputError("fit_divfree: lambda must be positive");
  Points p, v;
  merge_samples(points_in, velocities_in, opt.merge_distance, p, v);
  const int nc = static_cast<int>(p.rows());
  const bool with_boundary = opt.kernel == RbfKernel::Free && opt.boundary_samples.rows() > 0;
  const Eigen::Index nb = with_boundary ? opt.boundary_samples.rows() : 0;
  const Eigen::Index dim = 3 * nc + nb;
  if (opt.ridge > 0 && nb == 0 && dim > kSparseFitSize && !opt.estimate_condition)
    return fit_sparse(p, v, opt, static_cast<int>(points_in.rows() - nc), info);
  Eigen::MatrixXd a(dim, dim);
  a.topLeftCorner(3 * nc, 3 * nc) = gram(p, opt.kernel, opt.lambda);
  if (opt.ridge > 0 && nc > 0)
    a.diagonal().head(3 * nc).array() += opt.ridge * a.diagonal().head(3 * nc).mean();
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(dim);
  for (int i = 0; i < nc; ++i) rhs.segment<3>(3 * i) = v.row(i).transpose();
  const Points s = opt.boundary_samples.topRows(nb);
  add_boundary_constraints(a, p, s, opt.lambda);
  RbfFitInfo local;
  local.samples = nc;
  local.merged = static_cast<int>(points_in.rows() - nc);
  local.boundary_constraints = static_cast<int>(nb);
  if (opt.estimate_condition && dim > 0) {
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(a, Eigen::EigenvaluesOnly);
    const double lo = es.eigenvalues().minCoeff(), hi = es.eigenvalues().maxCoeff();
    local.condition = lo > 0 ? hi / lo : std::numeric_limits<double>::infinity();
  }
  Eigen::VectorXd sol;
  if (dim > 0 && opt.ridge > 0 && nb == 0 && dim > 1200)
    sol = solve_ridge_cg(a, rhs);
  else if (dim > 0)
    sol = solve_gram(a, rhs, opt.lambda, nc, local.regularised);
  DivFreeField f;
  f.kernel = opt.kernel;
  f.lambda = opt.lambda;
  f.centres.resize(nc + nb, 3);
  f.coefficients.resize(nc + nb, 3);
  for (int i = 0; i < nc; ++i) {
    f.centres.row(i) = p.row(i);
    f.coefficients.row(i) = sol.segment<3>(3 * i).transpose();
  }
  for (Eigen::Index j = 0; j < nb; ++j) {
    f.centres.row(nc + j) = s.row(j);
    f.coefficients.row(nc + j) = sol(3 * nc + j) * s.row(j).normalized();
  }
  for (int i = 0; i < nc; ++i)
    local.max_residual = std::max(
        local.max_residual, (f(p.row(i).transpose()) - v.row(i).transpose()).norm());
  if (info) *info = local;
  return f;
}

Eigen::VectorXd loo_errors(const Points& p, const Points& v, RbfKernel kind, double lambda) {
  const Eigen::Index n = p.rows();
  Eigen::VectorXd err = Eigen::VectorXd::Zero(n);
  if (n < 2) return err;
  const Eigen::MatrixXd a = gram(p, kind, lambda);
  Eigen::LLT<Eigen::MatrixXd> llt(a);
  if (llt.info() != Eigen::Success) {
    err.setConstant(std::numeric_limits<double>::infinity());
    return err;
  }
  const Eigen::MatrixXd inv = llt.solve(Eigen::MatrixXd::Identity(3 * n, 3 * n));
  Eigen::VectorXd rhs(3 * n);
  for (Eigen::Index i = 0; i < n; ++i) rhs.segment<3>(3 * i) = v.row(i).transpose();
  const Eigen::VectorXd c = inv * rhs;
  for (Eigen::Index j = 0; j < n; ++j) {
    const Eigen::Matrix3d b = inv.block<3, 3>(3 * j, 3 * j);
    err(j) = b.ldlt().solve(c.segment<3>(3 * j)).norm();
  }
  return err;
}

double mean_nearest_spacing(const Points& p) {
  const Eigen::Index n = p.rows();
  if (n < 2) return 0;
  double sum = 0;
  for (Eigen::Index i = 0; i < n; ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (Eigen::Index j = 0; j < n; ++j)
      if (j != i) best = std::min(best, (p.row(i) - p.row(j)).norm());
    sum += best;
  }
  return sum / static_cast<double>(n);
}

Points fibonacci_sphere(int n) {
  Points s(std::max(n, 0), 3);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - (2 * i + 1.0) / n;
    const double rho = std::sqrt(std::max(0.0, 1 - z * z));
    s.row(i) << rho * std::cos(golden * i), rho * std::sin(golden * i), z;
  }
  return s;
}

}  // namespace vpm
