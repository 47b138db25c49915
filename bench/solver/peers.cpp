#include "solver/peers.hpp"

#define VIENNACL_WITH_OPENCL
#include <viennacl/compressed_matrix.hpp>
#include <viennacl/linalg/cg.hpp>
#include <viennacl/linalg/jacobi_precond.hpp>
#include <viennacl/linalg/prod.hpp>
#include <viennacl/ocl/backend.hpp>
#include <viennacl/vector.hpp>

#include <Eigen/IterativeLinearSolvers>
#include <filesystem>
#include <random>

#include "linalg/solver_backend.hpp"
#include "support/shapes.hpp"
#include "core/device_cl.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "linalg/laplacian_device.hpp"
#include "vpm/timing.hpp"

namespace vpm::bench {

TetMesh problem_mesh(const std::string& source, std::string& name) {
  const std::string prefix = "ellipsoid:";
  if (source.rfind(prefix, 0) == 0) {
    const long target = std::stol(source.substr(prefix.size()));
    name = "ellipsoid-" + std::to_string(target / 1000) + "k";
    return test::voxel_ellipsoid_mesh(target);
  }
  name = std::filesystem::path(source).filename().string();
  return read_mesh(source);
}

Problem::Problem(Device& dev, std::string name_, TetMesh mesh_)
    : name(std::move(name_)),
      mesh(std::move(mesh_)),
      n(mesh.num_vertices()),
      solver(dev, n, mesh.tets) {
  solver.set_positions(mesh.vertices);
  K = solver.laplacian().matrix();
  nnz = K.nnz();
  std::mt19937 rng(42);
  std::normal_distribution<double> g;
  b.resize(n);
  for (int i = 0; i < n; ++i) b[i] = g(rng);
  b.array() -= b.mean();
  K_spd = K.to_eigen();
  K_spd = -K_spd;
  b_spd = -b;
}

namespace {

/// vpm's SpMV kernel on its own: the device's CSR kernel, or the host backend's product.
struct VpmSpmv {
  Device& dev;
  Problem& p;
  std::unique_ptr<detail::ClBackend> cl;
  std::unique_ptr<detail::HostBackend> host;

  double seconds() {
    if (!dev.is_host()) {
      if (!cl) {
        cl = std::make_unique<detail::ClBackend>(dev, p.n);
        auto L = const_cast<CotanLaplacian*>(&p.solver.laplacian());
        auto& buffers = L->device_state();
        cl->set_matrix(&buffers.row_ptr, &buffers.col, &buffers.val, nullptr, nullptr, nullptr);
        cl->upload(detail::VP, p.b.data());
        cl->spmv(detail::VQ, detail::VP, false);
        dev.cl().queue.finish();
      }
      const Stopwatch w;
      for (int k = 0; k < 20; ++k) cl->spmv(detail::VQ, detail::VP, false);
      dev.cl().queue.finish();
      return w.seconds() / 20;
    }
    if (!host) {
      host = std::make_unique<detail::HostBackend>(p.n);
      host->set_matrix(&p.K, nullptr);
      host->upload(detail::VP, p.b.data());
    }
    const Stopwatch w;
    for (int k = 0; k < 5; ++k) host->spmv(detail::VQ, detail::VP, false);
    return w.seconds() / 5;
  }
};

using EigenCG = Eigen::ConjugateGradient<CsrMatrix::EigenType, Eigen::Lower | Eigen::Upper,
                                         Eigen::DiagonalPreconditioner<double>>;

/// Eigen's CG with its last solution and iteration count.
struct EigenState {
  EigenCG cg;
  Eigen::VectorXd x;
  int iterations = 0;
};

/// The ViennaCL system shared by both ViennaCL peers: -K, -b, x, a product target and the
/// Jacobi preconditioner, on the device.
struct ViennaclState {
  using Matrix = viennacl::compressed_matrix<double>;
  explicit ViennaclState(const Problem& p)
      : A(p.n, p.n), b(p.n), x(p.n), y(p.n) {
    std::vector<unsigned int> rp(p.K.row_ptr.begin(), p.K.row_ptr.end()),
        cl(p.K.col.begin(), p.K.col.end());
    std::vector<double> vals(p.K_spd.valuePtr(), p.K_spd.valuePtr() + p.K_spd.nonZeros());
    A.set(rp.data(), cl.data(), vals.data(), p.n, p.n, p.nnz);
    viennacl::copy(p.b_spd.data(), p.b_spd.data() + p.n, b.begin());
    pc = std::make_unique<viennacl::linalg::jacobi_precond<Matrix>>(A, viennacl::linalg::jacobi_tag());
  }
  Matrix A;
  viennacl::vector<double> b, x, y;
  std::unique_ptr<viennacl::linalg::jacobi_precond<Matrix>> pc;
  int iterations = 0;
};

}  // namespace

Peer vpm_peer(Device& dev, Problem& p, double triad_gbs) {
  auto x = std::make_shared<Eigen::VectorXd>();
  auto spmv = std::make_shared<VpmSpmv>(VpmSpmv{dev, p, nullptr, nullptr});
  Peer e;
  e.solver = "vpm-cg";
  e.triad_gbs = triad_gbs;
  e.solve_once = [&p, x] {
    *x = Eigen::VectorXd::Zero(p.n);
    return p.solver.solve_neumann(p.b, *x).seconds;
  };
  e.iterations = [&p] { return p.solver.last_stats().iterations; };
  e.solution = [x] { return *x; };
  e.spmv_seconds = [spmv] { return spmv->seconds(); };
  return e;
}

Peer vpm_amg_peer(Device& dev, Problem& p, double triad_gbs, bool host) {
  struct State {
    std::shared_ptr<Device> host_device;
    std::unique_ptr<PoissonSolver> solver;
    Eigen::VectorXd x;
    double build = 0, update = 0;
    int iterations = 0;
  };
  auto s = std::make_shared<State>();
  if (host) s->host_device = Device::host();
  Device& d = host ? *s->host_device : dev;
  SolverOptions o;
  o.preconditioner = Preconditioner::amg;
  o.relative_tolerance = kTolerance;
  s->solver = std::make_unique<PoissonSolver>(d, p.n, p.mesh.tets, o);
  Peer e;
  e.solver = host ? "vpm-amg-cg-host" : "vpm-amg-cg";
  e.triad_gbs = triad_gbs;
  e.solve_once = [&p, s] {
    s->solver->set_positions(p.mesh.vertices);
    s->x = Eigen::VectorXd::Zero(p.n);
    const SolverStats st = s->solver->solve_neumann(p.b, s->x);
    s->iterations = st.iterations;
    if (s->build == 0) s->build = st.setup_seconds;
    else s->update = st.setup_seconds;
    return st.seconds - st.setup_seconds;
  };
  e.iterations = [s] { return s->iterations; };
  e.solution = [s] { return s->x; };
  e.spmv_seconds = [] { return 0.0; };
  e.setup_update_seconds = [s] { return s->update; };
  e.setup_build_seconds = [s] { return s->build; };
  return e;
}

std::vector<Peer> eigen_peers(const Problem& p, const std::vector<int>& thread_counts,
                              double host_triad_gbs) {
  std::vector<Peer> peers;
  for (int th : thread_counts) {
    auto s = std::make_shared<EigenState>();
    Peer e;
    e.solver = th == 1 ? "eigen-cg-1thread" : "eigen-cg";
    e.threads = th;
    e.triad_gbs = host_triad_gbs;
    e.solve_once = [&p, s, th] {
      Eigen::setNbThreads(th);
      s->cg.setTolerance(kTolerance);
      s->cg.setMaxIterations(20000);
      const Stopwatch w;
      s->cg.compute(p.K_spd);
      s->x = s->cg.solve(p.b_spd);
      const double sec = w.seconds();
      s->iterations = int(s->cg.iterations());
      if (s->cg.info() != Eigen::Success) throw NumericalError("Eigen CG did not converge");
      return sec;
    };
    e.iterations = [s] { return s->iterations; };
    e.solution = [s] { return s->x; };
    e.spmv_seconds = [&p, th] {
      Eigen::setNbThreads(th);
      Eigen::VectorXd y(p.n);
      const Stopwatch w;
      for (int k = 0; k < 5; ++k) y.noalias() = p.K_spd * p.b_spd;
      return w.seconds() / 5;
    };
    peers.push_back(std::move(e));
  }
  return peers;
}

std::string setup_viennacl(Device& dev) {
  try {
    viennacl::ocl::setup_context(7, dev.cl().context.get(), dev.cl().device.id(), dev.cl().queue.get());
    viennacl::ocl::switch_context(7);
    return "ok";
  } catch (const std::exception& e) {
    return std::string("setup failed: ") + e.what();
  }
}

std::vector<Peer> viennacl_peers(const Problem& p, double triad_gbs) {
  auto s = std::make_shared<ViennaclState>(p);
  std::vector<Peer> peers;
  for (const bool preconditioned : {true, false}) {
    Peer e;
    e.solver = preconditioned ? "viennacl-cg" : "viennacl-cg-pipelined-nopc";
    e.triad_gbs = triad_gbs;
    e.solve_once = [s, preconditioned] {
      viennacl::linalg::cg_tag tag(kTolerance, 20000);
      const Stopwatch w;
      s->x = preconditioned ? viennacl::linalg::solve(s->A, s->b, tag, *s->pc)
                            : viennacl::linalg::solve(s->A, s->b, tag);
      viennacl::backend::finish();
      const double sec = w.seconds();
      s->iterations = int(tag.iters());
      return sec;
    };
    e.iterations = [s] { return s->iterations; };
    e.solution = [s, n = p.n] {
      Eigen::VectorXd x(n);
      viennacl::copy(s->x.begin(), s->x.end(), x.data());
      return x;
    };
    e.spmv_seconds = [s] {
      const Stopwatch w;
      for (int k = 0; k < 20; ++k) s->y = viennacl::linalg::prod(s->A, s->b);
      viennacl::backend::finish();
      return w.seconds() / 20;
    };
    peers.push_back(std::move(e));
  }
  return peers;
}

}  // namespace vpm::bench
