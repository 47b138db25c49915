#include "vpm/solver.hpp"

#include <chrono>
#include <cmath>
#include <sstream>

#include "linalg/solver_backend.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"

namespace vpm {

namespace bc = boost::compute;
using detail::ClBackend;
using detail::HostBackend;

SolverMethod parse_solver_method(const std::string& name) {
  if (name == "cg") return SolverMethod::cg;
  if (name == "bicgstab") return SolverMethod::bicgstab;
  if (name == "paper") return SolverMethod::paper;
  throw InputError("--solver: unknown solver '" + name + "' (expected cg, bicgstab or paper)");
}

const char* to_string(SolverMethod m) {
  switch (m) {
    case SolverMethod::cg: return "cg";
    case SolverMethod::bicgstab: return "bicgstab";
    case SolverMethod::paper: return "paper";
  }
  return "?";
}

namespace {

using namespace detail;


[[noreturn]] void not_converged(SolverMethod m, double rel, int its, double tol, int n,
                                const char* why) {
  throw NumericalError(std::string("solver ") + to_string(m) + " " + why + ": relative residual " +
                       format_sig(rel, 3) + " after " + std::to_string(its) + " iterations (tolerance " +
                       format_sig(tol, 3) + ", " + std::to_string(n) + " unknowns)");
}

// y = (A D) x, or (A^T A D) x for the normal equations (uses VTMP).
template <class BK>
void apply_scaled(BK& bk, Vec y, Vec x, bool normal) {
  if (normal) {
    bk.spmv_scaled(VTMP, x);
    bk.spmv(y, VTMP, true);
  } else {
    bk.spmv_scaled(y, x);
  }
}

// The Krylov loop, written once for both backends. Precondition: VX holds the start, VR its
// residual (of the normal equations for `paper`). Runs until the recursive residual satisfies
// rr <= tol2 (one read of it per iteration; the device runs `lookahead` iterations ahead of
// the host so it never idles while the host checks). Returns the iterations done; *rr_out the
// last recursive squared residual. Throws NumericalError on breakdown or at `max_iterations`.
template <class BK>
int krylov(BK& bk, SolverMethod method, double tol2, int max_iterations, double* rr_out,
           double bnorm2, double tol) {
  const bool cg = method == SolverMethod::cg;
  const bool normal = method == SolverMethod::paper;
  if (cg) {
    bk.cg_init();
  } else {
    bk.copy(VR0, VR);
    bk.copy(VP, VR);
    bk.dot2(VR0, VR, VR, VR, OP_BI_INIT);
  }
  double rr = bk.read_rr_now();
  if (!std::isfinite(rr))
    not_converged(method, rr, 0, tol, bk.size(), "started from a non-finite residual");
  *rr_out = rr;
  if (rr <= tol2) return 0;
  if (max_iterations <= 0) not_converged(method, std::sqrt(rr / bnorm2), 0, tol, bk.size(), "did not converge");
  auto step = [&] {
    if (cg) {
      bk.spmv(VQ, VP, false);
      bk.dot(VP, VQ, OP_CG_ALPHA);
      bk.cg_update_xr();
      bk.cg_update_p();
    } else {
      apply_scaled(bk, VQ, VP, normal);  // v
      bk.dot(VR0, VQ, OP_BI_ALPHA);
      bk.bicg_s();
      apply_scaled(bk, VT, VS, normal);  // t
      bk.dot2(VT, VS, VT, VT, OP_BI_OMEGA);
      bk.bicg_update();
      bk.bicg_p();
    }
  };
  int enqueued = 0, done = 0;
  bool stop = false;
  while (true) {
    while (!stop && enqueued < max_iterations && enqueued < done + bk.lookahead()) {
      step();
      bk.request_rr(enqueued % 2);
      ++enqueued;
    }
    rr = bk.wait_rr(done % 2);
    ++done;
    *rr_out = rr;
    if (!std::isfinite(rr))
      not_converged(method, rr, done, tol, bk.size(), "broke down (non-finite residual)");
    if (rr <= tol2) {
      if (done == enqueued) return done;
      stop = true;  // the iteration already queued gives the result
    } else if (done == enqueued) {
      stop = false;
      if (done >= max_iterations)
        not_converged(method, std::sqrt(rr / bnorm2), done, tol, bk.size(), "did not converge");
    }
  }
}

// Solves A x = b on the backend (matrix, mask set). `b`, `x` length n; x in: start (fixed rows
// hold the Dirichlet values), out: solution. Fixed rows of x are not changed.
template <class BK>
SolverStats solve_system(BK& bk, const SolverOptions& opt, const std::vector<char>& mask,
                         const double* b, double* x) {
  const int n = bk.size();
  const bool normal = opt.method == SolverMethod::paper;
  SolverStats st;
  bk.set_preconditioner(normal);
  bk.upload(VB, b);
  // b_eff = b - A x_fixed on free rows
  std::vector<double> xc(x, x + n);
  for (int i = 0; i < n; ++i)
    if (!mask[i]) xc[i] = 0;
  bk.upload(VX, xc.data());
  bk.residual(VTMP, VB, VX);
  bk.dot(VTMP, VTMP, OP_NORM);
  const double borig2 = bk.read_rr_now();
  double bnorm2 = borig2;
  if (normal) {
    bk.spmv(VR, VTMP, true);
    bk.dot(VR, VR, OP_NORM);
    bnorm2 = bk.read_rr_now();
  }
  if (!std::isfinite(bnorm2))
    throw NumericalError("solver: the right-hand side (or the matrix) is not finite");
  if (bnorm2 == 0) {  // the solution is x_fixed and zero elsewhere
    std::copy(xc.begin(), xc.end(), x);
    return st;
  }
  const double tol = opt.relative_tolerance;
  const double tol2 = tol * tol * bnorm2;
  bk.upload(VX, x);
  auto true_residual = [&] {  // VR = residual (normal eqs for paper); returns its squared norm
    if (normal) {
      bk.residual(VTMP, VB, VX);
      bk.spmv(VR, VTMP, true);
    } else {
      bk.residual(VR, VB, VX);
    }
    bk.dot(VR, VR, OP_NORM);
    return bk.read_rr_now();
  };
  double rr_true = true_residual();
  for (int attempt = 0;; ++attempt) {
    double rr = 0;
    st.iterations += krylov(bk, opt.method, tol2, opt.max_iterations - st.iterations, &rr, bnorm2, tol);
    rr_true = true_residual();  // the recursive residual can drift from the true one
    if (rr_true <= tol2) break;
    if (attempt == 3 || st.iterations >= opt.max_iterations)
      not_converged(opt.method, std::sqrt(rr_true / bnorm2), st.iterations, tol, n,
                    "did not converge (true residual above tolerance after restarts)");
  }
  bk.download(VX, x);
  if (normal) {
    bk.residual(VTMP, VB, VX);
    bk.dot(VTMP, VTMP, OP_NORM);
    st.relative_residual = std::sqrt(bk.read_rr_now() / borig2);
  } else {
    st.relative_residual = std::sqrt(rr_true / bnorm2);
  }
  return st;
}


CsrMatrix transpose(const CsrMatrix& a) {
  CsrMatrix t;
  t.rows = a.cols;
  t.cols = a.rows;
  t.row_ptr.assign(t.rows + 1, 0);
  for (int c : a.col) ++t.row_ptr[c + 1];
  for (int i = 0; i < t.rows; ++i) t.row_ptr[i + 1] += t.row_ptr[i];
  t.col.resize(a.col.size());
  t.val.resize(a.val.size());
  std::vector<int> next(t.row_ptr.begin(), t.row_ptr.end() - 1);
  for (int r = 0; r < a.rows; ++r)
    for (int k = a.row_ptr[r]; k < a.row_ptr[r + 1]; ++k) {
      const int q = next[a.col[k]]++;
      t.col[q] = r;
      t.val[q] = a.val[k];
    }
  return t;
}

}  // namespace

// ------------------------------------------------------------------ SparseSolver ----------

struct SparseSolver::Impl {
  Device& device;
  CsrMatrix a, at;
  bool symmetric = true;
  std::vector<char> mask;
  std::unique_ptr<HostBackend> host;
  std::unique_ptr<ClBackend> cl;
  std::unique_ptr<bc::vector<int>> d_rp, d_col, d_trp, d_tcol;
  std::unique_ptr<bc::vector<double>> d_val, d_tval;
  explicit Impl(Device& d) : device(d) {}
};

SparseSolver::SparseSolver(Device& device, const CsrMatrix& a, SolverOptions options)
    : impl_(std::make_unique<Impl>(device)), options_(options) {
  if (a.rows != a.cols)
    throw InputError("SparseSolver: matrix is " + std::to_string(a.rows) + " x " +
                     std::to_string(a.cols) + ", not square");
  auto& s = *impl_;
  s.a = a;
  s.at = transpose(a);
  s.symmetric = s.at.row_ptr == a.row_ptr && s.at.col == a.col && s.at.val == a.val;
  s.mask.assign(a.rows, 0);
  if (device.is_host()) {
    s.host = std::make_unique<HostBackend>(a.rows);
    s.host->set_matrix(&s.a, s.symmetric ? nullptr : &s.at);
    s.host->set_mask(s.mask);
  } else {
    auto& q = device.queue();
    auto up_i = [&](const std::vector<int>& v) {
      auto p = std::make_unique<bc::vector<int>>(std::max<size_t>(v.size(), 1), device.context());
      if (!v.empty()) bc::copy(v.begin(), v.end(), p->begin(), q);
      return p;
    };
    auto up_d = [&](const std::vector<double>& v) {
      auto p = std::make_unique<bc::vector<double>>(std::max<size_t>(v.size(), 1), device.context());
      if (!v.empty()) bc::copy(v.begin(), v.end(), p->begin(), q);
      return p;
    };
    s.d_rp = up_i(s.a.row_ptr);
    s.d_col = up_i(s.a.col);
    s.d_val = up_d(s.a.val);
    if (!s.symmetric) {
      s.d_trp = up_i(s.at.row_ptr);
      s.d_tcol = up_i(s.at.col);
      s.d_tval = up_d(s.at.val);
    }
    s.cl = std::make_unique<ClBackend>(device, a.rows);
    s.cl->set_matrix(s.d_rp.get(), s.d_col.get(), s.d_val.get(), s.d_trp.get(), s.d_tcol.get(),
                     s.d_tval.get());
    s.cl->set_mask(s.mask);
  }
}

SparseSolver::~SparseSolver() = default;

SolverStats SparseSolver::solve(const Eigen::VectorXd& b, Eigen::VectorXd& x) {
  const auto t0 = Clock::now();
  auto& s = *impl_;
  const int n = s.a.rows;
  if (b.size() != n)
    throw InputError("SparseSolver::solve: right side has length " + std::to_string(b.size()) +
                     ", expected " + std::to_string(n));
  if (x.size() != n) x = Eigen::VectorXd::Zero(n);
  SolverStats st = s.host ? solve_system(*s.host, options_, s.mask, b.data(), x.data())
                          : solve_system(*s.cl, options_, s.mask, b.data(), x.data());
  st.seconds = seconds_since(t0);
  return st;
}

// ------------------------------------------------------------------ PoissonSolver ---------

struct PoissonSolver::Impl {
  std::unique_ptr<HostBackend> host;
  std::unique_ptr<ClBackend> cl;
  std::vector<char> mask;  // the mask the backend holds
  bool assembled = false;
  template <class F>
  auto with(F&& f) {
    return host ? f(*host) : f(*cl);
  }
  void set_mask(const std::vector<char>& m) {
    if (m == mask) return;
    mask = m;
    if (host) host->set_mask(mask);
    else cl->set_mask(mask);
  }
};

PoissonSolver::PoissonSolver(Device& device, int num_vertices, const Tets& tets, SolverOptions options)
    : device_(device), laplacian_(num_vertices, tets), options_(options), impl_(std::make_unique<Impl>()) {
  impl_->mask.assign(num_vertices, 0);
  if (device.is_host()) {
    impl_->host = std::make_unique<HostBackend>(num_vertices);
    impl_->host->set_mask(impl_->mask);
  } else {
    impl_->cl = std::make_unique<ClBackend>(device, num_vertices);
  }
}

PoissonSolver::~PoissonSolver() = default;

void PoissonSolver::set_positions(const Points& vertices) {
  laplacian_.assemble(device_, vertices);
  if (impl_->host) {
    impl_->host->set_matrix(&laplacian_.matrix(), nullptr);
  } else {
    impl_->cl->set_matrix(&laplacian_.device_row_ptr(), &laplacian_.device_col(),
                          &laplacian_.device_values(), nullptr, nullptr, nullptr);
  }
  impl_->assembled = true;
}

SolverStats PoissonSolver::solve_neumann(const Eigen::VectorXd& b_in, Eigen::VectorXd& x) {
  const auto t0 = Clock::now();
  const int n = laplacian_.num_vertices();
  if (!impl_->assembled) throw std::logic_error("PoissonSolver: set_positions() was not called");
  if (b_in.size() != n)
    throw InputError("PoissonSolver::solve_neumann: right side has length " +
                     std::to_string(b_in.size()) + ", expected " + std::to_string(n));
  const double sum = b_in.sum(), asum = b_in.cwiseAbs().sum();
  if (!std::isfinite(sum))
    throw InputError("PoissonSolver::solve_neumann: right side is not finite");
  if (std::abs(sum) > options_.neumann_tolerance * asum)
    throw InputError("PoissonSolver::solve_neumann: incompatible Neumann right side: sum " +
                     format_sig(sum, 3) + " vs sum|b| " + format_sig(asum, 3) + " (relative " + format_sig(sum / asum, 3) +
                     " > tolerance " + format_sig(options_.neumann_tolerance, 3) +
                     "); a singular Laplacian system needs a zero-sum right side");
  Eigen::VectorXd b = b_in.array() - (n > 0 ? sum / n : 0.0);
  if (x.size() != n) x = Eigen::VectorXd::Zero(n);
  impl_->set_mask(std::vector<char>(n, 0));
  SolverStats st =
      impl_->with([&](auto& bk) { return solve_system(bk, options_, impl_->mask, b.data(), x.data()); });
  if (n > 0) x.array() -= x.mean();
  st.seconds = seconds_since(t0);
  last_ = st;
  return st;
}

SolverStats PoissonSolver::solve_dirichlet(const std::vector<char>& fixed, const FieldValues& values,
                                           FieldValues& x, const FieldValues* rhs) {
  const auto t0 = Clock::now();
  const int n = laplacian_.num_vertices();
  if (!impl_->assembled) throw std::logic_error("PoissonSolver: set_positions() was not called");
  if (static_cast<int>(fixed.size()) != n)
    throw InputError("PoissonSolver::solve_dirichlet: fixed mask has length " +
                     std::to_string(fixed.size()) + ", expected " + std::to_string(n));
  if (values.rows() != n)
    throw InputError("PoissonSolver::solve_dirichlet: values have " + std::to_string(values.rows()) +
                     " rows, expected " + std::to_string(n));
  const Eigen::Index k = values.cols();
  if (rhs && (rhs->rows() != n || rhs->cols() != k))
    throw InputError("PoissonSolver::solve_dirichlet: rhs shape does not match values");
  std::vector<char> mask(n);
  bool any = false;
  for (int i = 0; i < n; ++i) {
    mask[i] = fixed[i] ? 1 : 0;
    any = any || mask[i];
  }
  if (!any && n > 0)
    throw InputError("PoissonSolver::solve_dirichlet: no vertex is fixed (the system is singular; "
                     "use solve_neumann)");
  if (x.rows() != n || x.cols() != k) x = FieldValues::Zero(n, k);
  impl_->set_mask(mask);
  SolverStats total;
  Eigen::VectorXd b(n), xc(n);
  for (Eigen::Index c = 0; c < k; ++c) {
    for (int i = 0; i < n; ++i) {
      b[i] = rhs ? (*rhs)(i, c) : 0.0;
      xc[i] = mask[i] ? values(i, c) : x(i, c);
    }
    const SolverStats st =
        impl_->with([&](auto& bk) { return solve_system(bk, options_, mask, b.data(), xc.data()); });
    total.iterations += st.iterations;
    total.relative_residual = std::max(total.relative_residual, st.relative_residual);
    x.col(c) = xc;
  }
  total.seconds = seconds_since(t0);
  last_ = total;
  return total;
}

// ------------------------------------------------------------------ one-call helpers ------

Eigen::VectorXd solve_neumann(const Points& vertices, const Tets& tets, const Eigen::VectorXd& b,
                              const SolverOptions& options, Device* device, SolverStats* stats) {
  Device& dev = device ? *device : Device::current();
  PoissonSolver s(dev, static_cast<int>(vertices.rows()), tets, options);
  s.set_positions(vertices);
  Eigen::VectorXd x;
  const SolverStats st = s.solve_neumann(b, x);
  if (stats) *stats = st;
  return x;
}

FieldValues solve_dirichlet(const Points& vertices, const Tets& tets, const std::vector<char>& fixed,
                            const FieldValues& values, const SolverOptions& options, Device* device,
                            SolverStats* stats) {
  Device& dev = device ? *device : Device::current();
  PoissonSolver s(dev, static_cast<int>(vertices.rows()), tets, options);
  s.set_positions(vertices);
  FieldValues x;
  const SolverStats st = s.solve_dirichlet(fixed, values, x);
  if (stats) *stats = st;
  return x;
}

Eigen::VectorXd solve(const CsrMatrix& a, const Eigen::VectorXd& b, const SolverOptions& options,
                      Device* device, SolverStats* stats) {
  Device& dev = device ? *device : Device::current();
  SparseSolver s(dev, a, options);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(a.rows);
  const SolverStats st = s.solve(b, x);
  if (stats) *stats = st;
  return x;
}

}  // namespace vpm
