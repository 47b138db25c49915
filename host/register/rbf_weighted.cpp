// ---- divergence-free fits to local least-squares data (vpm/rbf.hpp, fit_divfree_weighted) ----

#include "register/rbf_gram.hpp"
#include "vpm/error.hpp"
#include "vpm/rbf.hpp"

namespace vpm {

DivFreeField fit_divfree_weighted(const Points& centres, const LocalSystems& local, const RbfFitOptions& opt,
                                  RbfFitInfo* info) {
  if (!(opt.lambda > 0)) throw InputError("fit_divfree_weighted: lambda must be positive");
  const DivFreeField f = fit_divfree_weighted(centres, sparse_gram(centres, opt.kernel, opt.lambda), local, opt);
  if (info) {
    *info = RbfFitInfo{};
    info->samples = static_cast<int>(centres.rows());
  }
  return f;
}

DivFreeField fit_divfree_weighted(const Points& centres, const SparseGram& k, const LocalSystems& local,
                                  const RbfFitOptions& opt) {
  const Eigen::Index n = centres.rows();
  if (k.rows() != 3 * n) throw InputError("fit_divfree_weighted: the Gram matrix does not match the centres");
  if (static_cast<Eigen::Index>(local.a.size()) != n || local.b.rows() != n)
    throw InputError("fit_divfree_weighted: " + std::to_string(n) + " centres but " +
                     std::to_string(local.a.size()) + " local systems");
  if (!(opt.lambda > 0) || !(opt.ridge > 0)) throw InputError("fit_divfree_weighted: lambda and ridge must be positive");
  if (!(opt.tolerance > 0 && opt.tolerance < 1)) throw InputError("fit_divfree_weighted: the tolerance must lie in (0, 1)");
  if (opt.boundary_samples.rows() > 0) throw InputError("fit_divfree_weighted: boundary samples are not supported");
  DivFreeField f;
  f.kernel = opt.kernel;
  f.lambda = opt.lambda;
  f.centres = centres;
  f.coefficients = Points::Zero(n, 3);
  if (n == 0) return f;
  double trace = 0;
  for (const Eigen::Matrix3d& a : local.a) trace += a.trace();
  const double mu = opt.ridge * k.diagonal().mean() * trace / (3.0 * static_cast<double>(n));
  if (!(mu > 0)) return f;  // no data anywhere: no motion
  auto apply_a = [&](const Eigen::VectorXd& v) {  // the block diagonal A
    Eigen::VectorXd out(v.size());
    for (Eigen::Index j = 0; j < n; ++j) out.segment<3>(3 * j) = local.a[static_cast<size_t>(j)] * v.segment<3>(3 * j);
    return out;
  };
  Eigen::VectorXd rhs(3 * n);
  for (Eigen::Index j = 0; j < n; ++j) rhs.segment<3>(3 * j) = local.b.row(j).transpose();
  // CG for T x = rhs, T = A K + mu I, in the inner product <x, y> = x^T K y where T is
  // self-adjoint and positive definite; K p is carried along, so one Gram product per iteration.
  Eigen::VectorXd x = Eigen::VectorXd::Zero(3 * n), r = rhs, kr = multiply(k, r), p = r, kp = kr;
  double rr = r.dot(kr);
  const double stop = opt.tolerance * opt.tolerance * rr;
  for (Eigen::Index it = 0; it < 3 * n + 100 && rr > stop; ++it) {
    const Eigen::VectorXd tp = apply_a(kp) + mu * p;
    const double alpha = rr / kp.dot(tp);
    x += alpha * p;
    r -= alpha * tp;
    kr = multiply(k, r);
    const double next = r.dot(kr);
    p = r + (next / rr) * p;
    kp = kr + (next / rr) * kp;
    rr = next;
  }
  for (Eigen::Index j = 0; j < n; ++j) f.coefficients.row(j) = x.segment<3>(3 * j).transpose();
  return f;
}

}  // namespace vpm
