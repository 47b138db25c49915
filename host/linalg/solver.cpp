#include "vpm/solver.hpp"

#include <cmath>
#include <sstream>
#include <type_traits>
#include <variant>

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

PreconditionerChoice parse_preconditioner_choice(const std::string& name) {
  if (name == "auto") return PreconditionerChoice::automatic;
  if (name == "jacobi") return PreconditionerChoice::jacobi;
  if (name == "amg") return PreconditionerChoice::amg;
  throw InputError("unknown preconditioner '" + name + "' (expected auto, jacobi or amg)");
}

const char* to_string(PreconditionerChoice c) {
  return c == PreconditionerChoice::automatic ? "auto" : c == PreconditionerChoice::amg ? "amg" : "jacobi";
}

Preconditioner choose_preconditioner(PreconditionerChoice choice, const Device& device, long long tets) {
  if (choice == PreconditionerChoice::jacobi) return Preconditioner::jacobi;
  if (choice == PreconditionerChoice::amg) return Preconditioner::amg;
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

namespace {

// The matrix and its transpose in device buffers, for the OpenCL backend (kept alive with it).
struct ClMatrix {
  std::unique_ptr<bc::vector<int>> rp, col, trp, tcol;
  std::unique_ptr<bc::vector<double>> val, tval;
};

// The OpenCL backend with the buffers it points into.
struct ClSide {
  ClMatrix m;
  std::unique_ptr<ClBackend> bk;
};

}  // namespace

struct SparseSolver::Impl {
  Device& device;
  CsrMatrix a, at;
  bool symmetric = true;
  std::vector<char> mask;
  std::variant<std::unique_ptr<HostBackend>, ClSide> side;  // by the device, at construction
  detail::AmgState amg;
  explicit Impl(Device& d) : device(d) {}
  // f(backend) on the side the device chose
  template <class F>
  auto with(F&& f) {
    return std::visit([&](auto& sd) {
      if constexpr (std::is_same_v<std::decay_t<decltype(sd)>, ClSide>) return f(*sd.bk);
      else return f(*sd);
    }, side);
  }
};

namespace {

std::unique_ptr<HostBackend> host_side(const CsrMatrix& a, const CsrMatrix* at, const std::vector<char>& mask) {
  auto bk = std::make_unique<HostBackend>(a.rows);
  bk->set_matrix(&a, at);
  bk->set_mask(mask);
  return bk;
}

ClSide device_side(Device& device, const CsrMatrix& a, const CsrMatrix* at, const std::vector<char>& mask) {
  auto& q = device.cl().queue;
  auto up = [&](const auto& v) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    auto p = std::make_unique<bc::vector<T>>(std::max<size_t>(v.size(), 1), device.cl().context);
    if (!v.empty()) bc::copy(v.begin(), v.end(), p->begin(), q);
    return p;
  };
  ClSide sd;
  sd.m.rp = up(a.row_ptr);
  sd.m.col = up(a.col);
  sd.m.val = up(a.val);
  if (at) {
    sd.m.trp = up(at->row_ptr);
    sd.m.tcol = up(at->col);
    sd.m.tval = up(at->val);
  }
  sd.bk = std::make_unique<ClBackend>(device, a.rows);
  sd.bk->set_matrix(sd.m.rp.get(), sd.m.col.get(), sd.m.val.get(), sd.m.trp.get(), sd.m.tcol.get(), sd.m.tval.get());
  sd.bk->set_mask(mask);
  return sd;
}

}  // namespace

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
  const CsrMatrix* at = s.symmetric ? nullptr : &s.at;
  if (device.is_host()) s.side = host_side(s.a, at, s.mask);
  else s.side = device_side(device, s.a, at, s.mask);
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
  SolverStats st = s.with([&](auto& bk) {
    detail::use_amg(bk, amg ? &s.amg : nullptr);
    return solve_system(bk, options_, s.mask, b.data(), x.data());
  });
  st.seconds = seconds_since(t0);
  st.setup_seconds = setup;
  return st;
}

}  // namespace vpm
