#include "vpm/solver.hpp"

#include <cmath>
#include <sstream>

#include "linalg/amg_state.hpp"
#include "linalg/csr_ops.hpp"
#include "linalg/krylov.hpp"
#include "linalg/solver_backend.hpp"
#include "core/device_cl.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"

namespace vpm {

namespace bc = boost::compute;
using detail::ClBackend;
using detail::HostBackend;
using detail::solve_system;

SolverMethod parse_solver_method(const std::string& name) {
  if (name == "cg") return SolverMethod::cg;
  if (name == "bicgstab") return SolverMethod::bicgstab;
  if (name == "paper") return SolverMethod::paper;
  throw InputError("unknown solver '" + name + "' (expected cg, bicgstab or paper)");
}

Preconditioner parse_preconditioner(const std::string& name) {
  if (name == "jacobi") return Preconditioner::jacobi;
  if (name == "amg") return Preconditioner::amg;
  throw InputError("unknown preconditioner '" + name + "' (expected jacobi or amg)");
}

Preconditioner choose_preconditioner(const std::string& name, const Device& device, long long tets) {
  if (name != "auto") return parse_preconditioner(name);
  const bool cpu = device.is_host() || device.description().kind == DeviceKind::cpu;
  return cpu && tets >= kAutoAmgTets ? Preconditioner::amg : Preconditioner::jacobi;
}

const char* to_string(Preconditioner p) { return p == Preconditioner::amg ? "amg" : "jacobi"; }

const char* to_string(SolverMethod m) {
  switch (m) {
    case SolverMethod::cg: return "cg";
    case SolverMethod::bicgstab: return "bicgstab";
    case SolverMethod::paper: return "paper";
  }
  return "?";
}

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
  detail::AmgState amg;
  explicit Impl(Device& d) : device(d) {}
};

SparseSolver::SparseSolver(Device& device, const CsrMatrix& a, SolverOptions options)
    : impl_(std::make_unique<Impl>(device)), options_(options) {
  if (a.rows != a.cols)
    throw InputError("SparseSolver: matrix is " + std::to_string(a.rows) + " x " +
                     std::to_string(a.cols) + ", not square");
  auto& s = *impl_;
  s.a = a;
  s.at = detail::csr_transpose(a);
  s.symmetric = s.at.row_ptr == a.row_ptr && s.at.col == a.col && s.at.val == a.val;
  s.mask.assign(a.rows, 0);
  if (device.is_host()) {
    s.host = std::make_unique<HostBackend>(a.rows);
    s.host->set_matrix(&s.a, s.symmetric ? nullptr : &s.at);
    s.host->set_mask(s.mask);
  } else {
    auto& q = device.cl().queue;
    auto up_i = [&](const std::vector<int>& v) {
      auto p = std::make_unique<bc::vector<int>>(std::max<size_t>(v.size(), 1), device.cl().context);
      if (!v.empty()) bc::copy(v.begin(), v.end(), p->begin(), q);
      return p;
    };
    auto up_d = [&](const std::vector<double>& v) {
      auto p = std::make_unique<bc::vector<double>>(std::max<size_t>(v.size(), 1), device.cl().context);
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
  const bool amg = options_.preconditioner == Preconditioner::amg && options_.method == SolverMethod::cg;
  double setup = 0;
  if (amg) setup = s.amg.prepare(&s.device, s.a, s.mask, options_.amg);
  if (s.host) s.host->set_amg(amg ? s.amg.host.get() : nullptr);
  else s.cl->set_amg(amg ? s.amg.device.get() : nullptr);
  SolverStats st = s.host ? solve_system(*s.host, options_, s.mask, b.data(), x.data())
                          : solve_system(*s.cl, options_, s.mask, b.data(), x.data());
  st.seconds = seconds_since(t0);
  st.setup_seconds = setup;
  return st;
}

}  // namespace vpm
