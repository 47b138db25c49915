// PoissonSolver and the one-call solve functions (vpm/solver.hpp), over the Krylov solvers of
// linalg/krylov.hpp.
#include "vpm/solver.hpp"

#include <cmath>
#include <type_traits>
#include <variant>

#include "linalg/amg_state.hpp"
#include "linalg/krylov.hpp"
#include "linalg/laplacian_device.hpp"
#include "linalg/krylov_block.hpp"
#include "linalg/solver_backend.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"

namespace vpm {

namespace bc = boost::compute;
using detail::ClBackend;
using detail::HostBackend;
using detail::solve_system;

namespace {

// One side's backends: the main one first, then the further columns of block solves
// (solve_dirichlet with several columns), on the same matrix and mask, made on first use.
template <class BK>
struct Backends {
  std::vector<std::unique_ptr<BK>> list;
};

}  // namespace

struct PoissonSolver::Impl {
  std::variant<Backends<HostBackend>, Backends<ClBackend>> side;  // by the device, at construction
  std::vector<char> mask;  // the mask the backends hold
  bool assembled = false;
  detail::AmgState amg_neumann, amg_dirichlet;  // one hierarchy per kind of solve
  CotanLaplacian* matrix = nullptr;             // what set_positions gave the backends

  // f(b) for every backend b of the side the device chose
  template <class F>
  void each(F&& f) {
    std::visit([&](auto& bs) {
      for (auto& b : bs.list) f(*b);
    }, side);
  }
  // f(the main backend)
  template <class F>
  auto with(F&& f) {
    return std::visit([&](auto& bs) { return f(*bs.list.front()); }, side);
  }
  /// Selects Jacobi or the (refreshed) AMG hierarchy for `mask` on the backend; returns the
  /// setup seconds.
  double prepare(Device& dev, const CotanLaplacian& lap, const SolverOptions& o, bool dirichlet) {
    const bool use = o.preconditioner == Preconditioner::amg && o.method == SolverMethod::cg;
    double t = 0;
    detail::AmgState& st = dirichlet ? amg_dirichlet : amg_neumann;
    if (use) t = st.prepare(&dev, lap.matrix(), mask, o.amg);
    with([&](auto& bk) { detail::use_amg(bk, use ? &st : nullptr); });
    return t;
  }
  void set_mask(const std::vector<char>& m) {
    if (m == mask) return;
    mask = m;
    each([&](auto& b) { b.set_mask(mask); });
  }
  static void give_matrix(HostBackend& b, CotanLaplacian& lap) { b.set_matrix(&lap.matrix(), nullptr); }
  static void give_matrix(ClBackend& b, CotanLaplacian& lap) {
    auto& s = lap.device_state();
    b.set_matrix(&s.row_ptr, &s.col, &s.val, nullptr, nullptr, nullptr);
  }
  void set_matrix(CotanLaplacian& lap) {
    matrix = &lap;
    each([&](auto& b) { give_matrix(b, lap); });
  }
  // The k backends of a block solve (the main one first).
  template <class BK>
  std::vector<BK*> columns(Device& dev, int n, int k, Backends<BK>& bs) {
    while (static_cast<int>(bs.list.size()) < k) {
      if constexpr (std::is_same_v<BK, HostBackend>) bs.list.push_back(std::make_unique<BK>(n));
      else bs.list.push_back(std::make_unique<BK>(dev, n));
      bs.list.back()->set_mask(mask);
      give_matrix(*bs.list.back(), *matrix);
    }
    std::vector<BK*> out;
    for (int c = 0; c < k; ++c) out.push_back(bs.list[static_cast<size_t>(c)].get());
    return out;
  }
  // Solves the columns of b into those of x (start in, solution out): one column alone, more
  // as a block.
  std::vector<SolverStats> solve_columns(Device& dev, const SolverOptions& o, const Eigen::MatrixXd& b,
                                         Eigen::MatrixXd& x) {
    const int n = static_cast<int>(b.rows()), k = static_cast<int>(b.cols());
    if (k == 1) return {with([&](auto& bk) { return solve_system(bk, o, mask, b.data(), x.data()); })};
    std::vector<const double*> bp;
    std::vector<double*> xp;
    for (int c = 0; c < k; ++c) {
      bp.push_back(b.col(c).data());
      xp.push_back(x.col(c).data());
    }
    return std::visit([&](auto& bs) { return detail::solve_system_block(columns(dev, n, k, bs), o, mask, bp, xp); },
                      side);
  }
  // Back to the main backend with Jacobi (the further columns and the hierarchies go).
  void release() {
    std::visit([&](auto& bs) { bs.list.resize(1); }, side);
    amg_neumann = detail::AmgState{};
    amg_dirichlet = detail::AmgState{};
    with([&](auto& bk) { detail::use_amg(bk, nullptr); });
  }
};

PoissonSolver::PoissonSolver(Device& device, int num_vertices, const Tets& tets, SolverOptions options)
    : device_(device), laplacian_(num_vertices, tets), options_(options), impl_(std::make_unique<Impl>()) {
  impl_->mask.assign(num_vertices, 0);
  if (device.is_host()) {
    Backends<HostBackend> bs;
    bs.list.push_back(std::make_unique<HostBackend>(num_vertices));
    bs.list.front()->set_mask(impl_->mask);
    impl_->side = std::move(bs);
  } else {
    Backends<ClBackend> bs;
    bs.list.push_back(std::make_unique<ClBackend>(device, num_vertices));
    impl_->side = std::move(bs);
  }
}

PoissonSolver::~PoissonSolver() = default;

void PoissonSolver::release_work_memory() { impl_->release(); }

void PoissonSolver::set_positions(const Points& vertices) {
  laplacian_.assemble(device_, vertices);
  impl_->set_matrix(laplacian_);
  impl_->assembled = true;
  impl_->amg_neumann.stale = impl_->amg_dirichlet.stale = true;
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
  const double setup = impl_->prepare(device_, laplacian_, options_, false);
  SolverStats st =
      impl_->with([&](auto& bk) { return solve_system(bk, options_, impl_->mask, b.data(), x.data()); });
  st.setup_seconds = setup;
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
  total.setup_seconds = impl_->prepare(device_, laplacian_, options_, true);
  // with Jacobi CG, up to kMaxBlock columns at once (one pass over the matrix per iteration for
  // all): the same result, column by column, as solving them one at a time
  const bool block = options_.method == SolverMethod::cg && options_.preconditioner == Preconditioner::jacobi;
  const Eigen::Index step = block ? detail::kMaxBlock : 1;
  for (Eigen::Index c0 = 0; c0 < k; c0 += step) {
    const int kb = static_cast<int>(std::min(step, k - c0));
    Eigen::MatrixXd b(n, kb), xc(n, kb);
    for (int c = 0; c < kb; ++c)
      for (int i = 0; i < n; ++i) {
        b(i, c) = rhs ? (*rhs)(i, c0 + c) : 0.0;
        xc(i, c) = mask[i] ? values(i, c0 + c) : x(i, c0 + c);
      }
    const std::vector<SolverStats> st = impl_->solve_columns(device_, options_, b, xc);
    for (int c = 0; c < kb; ++c) {
      total.iterations += st[static_cast<size_t>(c)].iterations;
      total.relative_residual = std::max(total.relative_residual, st[static_cast<size_t>(c)].relative_residual);
      x.col(c0 + c) = xc.col(c);
    }
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