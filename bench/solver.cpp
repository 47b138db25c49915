// vpm_bench_solver: our CG on the selected device (VPM_DEVICE) against Eigen's CG on the host
// and ViennaCL 1.7.1's CG on the same OpenCL device, on cotangent Laplacians of jittered
// structured tet meshes of an ellipsoid (1.8 : 1 : 0.6) and of given meshes. Prints a table and writes JSON
// (docs/solver.md). The peers are in solver/peers.cpp.
//
//   vpm_bench_solver [--sizes 25000,100000,400000,1600000] [--meshes A.vtu,B.vtu] [--quick]
//                    [--repeats 5] [--json solver.json] [--no-viennacl] [--no-eigen] [--no-amg]
//                    [--eigen-threads N] [--hypre-ranks 1,2 | --no-hypre]   (solver/options.hpp)
// AMG peers (vpm-amg-cg on the device, vpm-amg-cg-host): median_s is the solve without the
// hierarchy update, reported as setup_update_s (median) and setup_build_s (first build).
//
// hypre's BoomerAMG-CG (hypre-boomeramg-cg-<N>rank, solver/hypre_run.hpp): median_s is its
// solve, setup_update_s its BoomerAMG setup (a full rebuild: hypre cannot reuse a pattern).
//
// --eigen-threads N: Eigen with N threads only (default: all hardware threads and 1, both run).
#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>
#include <thread>
#include <vector>

#include "solver/hypre_run.hpp"
#include "solver/options.hpp"
#include "solver/peers.hpp"
#include <boost/compute/container/vector.hpp>

#include "core/device_cl.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"
#include "vpm/timing.hpp"

using namespace vpm;
using namespace vpm::bench;
namespace bc = boost::compute;

namespace {

std::string machine_name() {
  std::ifstream in("/proc/cpuinfo");
  std::string line, model = "unknown CPU";
  while (std::getline(in, line))
    if (line.rfind("model name", 0) == 0) {
      model = line.substr(line.find(':') + 2);
      break;
    }
  return model + ", " + std::to_string(std::thread::hardware_concurrency()) + " hardware threads";
}

std::string loadavg() {
  std::ifstream in("/proc/loadavg");
  std::string a, b, c;
  in >> a >> b >> c;
  return a + " " + b + " " + c;
}

/// Triad a = b + 0.5 c bandwidth in GB/s (median of 10), on the device and on the host.
struct Triad {
  double device_gbs = 0, host_gbs = 0;
};

Triad measure_triad(Device& dev) {
  const int tn = 1 << 23;
  Triad r;
  Eigen::VectorXd A = Eigen::VectorXd::Zero(tn), B = Eigen::VectorXd::Constant(tn, 1.0),
                  C = Eigen::VectorXd::Constant(tn, 2.0);
  std::vector<double> t;
  for (int k = 0; k < 10; ++k) {
    const Stopwatch w;
#pragma omp parallel for
    for (int i = 0; i < tn; ++i) A[i] = B[i] + 0.5 * C[i];
    t.push_back(w.seconds());
  }
  r.host_gbs = 24.0 * tn / median(t) / 1e9;
  if (dev.is_host()) {
    r.device_gbs = r.host_gbs;
    return r;
  }
  auto& q = dev.cl().queue;
  bc::vector<double> a(tn, dev.cl().context), b(B.data(), B.data() + tn, q), c(C.data(), C.data() + tn, q);
  auto kernel = dev.cl().kernel("solver", "triad", dev.description().kind == DeviceKind::cpu ? "-DCHUNKED" : "");
  kernel.set_args(tn, 0.5, a, b, c);
  dev.cl().launch(kernel, tn);
  q.finish();
  t.clear();
  for (int k = 0; k < 10; ++k) {
    const Stopwatch w;
    dev.cl().launch(kernel, tn);
    q.finish();
    t.push_back(w.seconds());
  }
  r.device_gbs = 24.0 * tn / median(t) / 1e9;
  return r;
}

/// One solver on one mesh: a row of the table and of the JSON.
struct Run {
  std::string mesh, solver;
  long tets = 0, vertices = 0, nnz = 0;
  double median_s = 0, relative_residual = 0, spmv_gbs = 0, spmv_fraction = 0;
  int iterations = 0;
  int threads = 0;
  std::vector<double> times, update_times;  ///< AMG: hierarchy value updates per solve
  double build_s = 0;                       ///< AMG: the first full hierarchy build
  std::string note;
};

double spmv_bytes(long n, long nnz) { return 12.0 * nnz + 4.0 * (n + 1) + 16.0 * n + n; }

/// Times the peers on the problem: a warm-up (kernel builds, first launches), then the repeats
/// interleaved round-robin so that load changes on the shared machine hit every solver alike.
std::vector<Run> time_peers(const Problem& p, std::vector<Peer>& peers, int repeats) {
  std::vector<Run> runs;
  for (const Peer& e : peers) {
    Run r;
    r.mesh = p.name;
    r.solver = e.solver;
    r.tets = p.mesh.num_tets();
    r.vertices = p.n;
    r.nnz = p.nnz;
    r.threads = e.threads;
    runs.push_back(r);
  }
  for (size_t q = 0; q < peers.size(); ++q) {
    try {
      peers[q].solve_once();
      peers[q].spmv_seconds();
    } catch (const std::exception& ex) {
      runs[q].note = std::string("failed: ") + ex.what();
    }
  }
  std::vector<std::vector<double>> spmv_t(peers.size());
  for (int rep = 0; rep < repeats; ++rep)
    for (size_t q = 0; q < peers.size(); ++q) {
      Run& r = runs[q];
      if (!r.note.empty()) continue;
      try {
        r.times.push_back(peers[q].solve_once());
        r.iterations = peers[q].iterations();
        if (peers[q].setup_update_seconds) {
          r.update_times.push_back(peers[q].setup_update_seconds());
          r.build_s = peers[q].setup_build_seconds();
        }
        if (rep == repeats - 1)
          r.relative_residual = (p.K.multiply(peers[q].solution()) - p.b).norm() / p.b.norm();
        if (!peers[q].setup_update_seconds) spmv_t[q].push_back(peers[q].spmv_seconds());
      } catch (const std::exception& ex) {
        r.note = std::string("failed: ") + ex.what();
      }
    }
  for (size_t q = 0; q < peers.size(); ++q) {
    Run& r = runs[q];
    if (!r.times.empty()) r.median_s = median(r.times);
    if (!spmv_t[q].empty()) {
      r.spmv_gbs = spmv_bytes(p.n, p.nnz) / median(spmv_t[q]) / 1e9;
      r.spmv_fraction = r.spmv_gbs / peers[q].triad_gbs;
    }
    if (r.solver.rfind("viennacl", 0) == 0 && r.relative_residual > kTolerance)
      r.note += (r.note.empty() ? "" : "; ") +
                std::string("ViennaCL stops on its recursive residual; the true residual is slightly above 1e-8");
  }
  return runs;
}

/// hypre's BoomerAMG-CG with `ranks` MPI processes on the same problem (its own program, which
/// rebuilds the problem: the same mesh and right-hand side), as a row of the table.
Run run_hypre_peer(const Problem& p, const std::string& source, int ranks, int repeats) {
  Run r;
  r.mesh = p.name;
  r.solver = "hypre-boomeramg-cg-" + std::to_string(ranks) + "rank";
  r.tets = p.mesh.num_tets();
  r.vertices = p.n;
  r.nnz = p.nnz;
  r.threads = ranks;
  try {
    const HypreRun h = run_hypre(source, ranks, repeats, p.n, p.nnz);
    r.times = h.solve_s;
    r.update_times = h.setup_s;
    r.median_s = median(r.times);
    r.build_s = r.update_times.front();
    r.iterations = h.iterations;
    r.relative_residual = h.relative_residual;
    r.note = "separate process under mpirun, after the other peers; BoomerAMG rebuilt per solve "
             "(setup_update_s); " + h.settings;
    if (r.relative_residual > 2 * kTolerance) {  // its PCG can report convergence above it
      r.note = "did not reach the tolerance (true relative residual " + std::to_string(r.relative_residual) +
               "): times not comparable; " + r.note;
      std::cerr << r.solver << " on " << r.mesh << ": " << r.note.substr(0, r.note.find(';')) << "\n";
    }
  } catch (const std::exception& ex) {
    r.note = std::string("failed: ") + ex.what();
  }
  return r;
}

/// Builds the problem of one size and runs every peer on it. A ViennaCL failure is recorded in
/// `viennacl_status`, and ViennaCL is not run on the later sizes.
std::vector<Run> run_size(Device& dev, const std::string& source, const SolverBenchOptions& o, const Triad& triad,
                          std::string& viennacl_status, const std::string& hypre_status) {
  std::string name;
  TetMesh mesh = problem_mesh(source, name);
  Problem p(dev, name, std::move(mesh));
  std::cerr << "\n" << name << ": " << p.n << " vertices, " << p.mesh.num_tets() << " tets\n";
  std::vector<Peer> peers = {vpm_peer(dev, p, triad.device_gbs)};
  if (o.use_amg) {
    peers.push_back(vpm_amg_peer(dev, p, triad.device_gbs, false));
    if (!dev.is_host()) peers.push_back(vpm_amg_peer(dev, p, triad.host_gbs, true));
  }
  if (o.use_eigen)
    for (Peer& e : eigen_peers(p, o.eigen_threads, triad.host_gbs)) peers.push_back(std::move(e));
  if (viennacl_status == "ok") {
    try {
      for (Peer& e : viennacl_peers(p, triad.device_gbs)) peers.push_back(std::move(e));
    } catch (const std::exception& ex) {
      viennacl_status = std::string("failed on ") + name + ": " + ex.what();
      std::cerr << "ViennaCL: " << viennacl_status << "\n";
    }
  }
  std::vector<Run> runs = time_peers(p, peers, o.repeats);
  if (hypre_status == "ok")
    for (int ranks : o.hypre_ranks) runs.push_back(run_hypre_peer(p, source, ranks, o.repeats));
  std::cerr << "done " << name << " (load " << loadavg() << ")\n";
  return runs;
}

double us_per_iteration_per_mnnz(const Run& r) {
  return r.iterations > 0 ? r.median_s / r.iterations / (r.nnz / 1e6) * 1e6 : 0;
}

void print_table(const std::vector<Run>& runs) {
  std::printf("\n%-16s %9s %9s %-28s %10s %6s %10s %9s %7s %12s %9s %9s\n", "mesh", "tets", "nnz",
              "solver", "median_s", "iters", "rel_res", "spmv_GB/s", "%triad", "us/it/Mnnz",
              "update_s", "build_s");
  for (const auto& r : runs)
    std::printf("%-16s %9ld %9ld %-28s %10.4f %6d %10.2e %9.2f %6.0f%% %12.1f %9.4f %9.4f\n",
                r.mesh.c_str(), r.tets, r.nnz, r.solver.c_str(), r.median_s, r.iterations,
                r.relative_residual, r.spmv_gbs, 100 * r.spmv_fraction, us_per_iteration_per_mnnz(r),
                r.update_times.empty() ? 0.0 : median(r.update_times), r.build_s);
}

Json to_json(const Run& r) {
  Json j = Json::object();
  j["mesh"] = r.mesh;
  j["tets"] = r.tets;
  j["vertices"] = r.vertices;
  j["nnz"] = r.nnz;
  j["solver"] = r.solver;
  j["median_s"] = r.median_s;
  Json ts = Json::array();
  for (double t : r.times) ts.push_back(t);
  j["times_s"] = ts;
  j["iterations"] = r.iterations;
  j["relative_residual"] = r.relative_residual;
  j["spmv_gbs"] = r.spmv_gbs;
  j["spmv_fraction_of_triad"] = r.spmv_fraction;
  j["us_per_iteration_per_mnnz"] = us_per_iteration_per_mnnz(r);
  if (!r.update_times.empty()) {
    Json us = Json::array();
    for (double t : r.update_times) us.push_back(t);
    j["setup_update_times_s"] = us;
    j["setup_update_s"] = median(r.update_times);
    j["setup_build_s"] = r.build_s;
    j["median_with_update_s"] = r.median_s + median(r.update_times);
  }
  if (!r.note.empty()) j["note"] = r.note;
  if (r.threads > 0) j["threads"] = r.threads;
  return j;
}

/// Per mesh: each peer's median time over vpm's ("<solver>_over_vpm").
Json speedups(const std::vector<Run>& runs) {
  Json ratios = Json::array();
  for (const auto& r : runs) {
    if (r.solver != "vpm-cg") continue;
    Json q = Json::object();
    q["mesh"] = r.mesh;
    for (const auto& p : runs)
      if (p.mesh == r.mesh && p.solver != "vpm-cg") q[p.solver + "_over_vpm"] = p.median_s / r.median_s;
    ratios.push_back(q);
  }
  return ratios;
}

/// The runs of the contract solvers go to "runs", the others (1 thread, pipelined) to
/// "extra_runs".
void add_runs(Json& out, const std::vector<Run>& runs) {
  Json arr = Json::array(), extra = Json::array();
  for (const auto& r : runs) {
    const bool contract = r.solver == "vpm-cg" || r.solver == "eigen-cg" || r.solver == "viennacl-cg" ||
                          r.solver.rfind("vpm-amg", 0) == 0 || r.solver.rfind("hypre", 0) == 0;
    (contract ? arr : extra).push_back(to_json(r));
  }
  out["runs"] = arr;
  out["extra_runs"] = extra;
}

std::string viennacl_start_status(Device& dev, bool use_viennacl) {
  if (dev.is_host()) return "skipped: VPM_DEVICE=host has no OpenCL device";
  return use_viennacl ? setup_viennacl(dev) : "not run";
}

}  // namespace

int main(int argc, char** argv) try {
  SolverBenchOptions o = parse_solver_bench_options(argc, argv);
  if (o.help) {
    std::cout << "vpm_bench_solver [--sizes N,N,...] [--quick] [--repeats R] [--json FILE] "
                 "[--no-viennacl] [--no-eigen] [--no-amg] [--eigen-threads N] [--hypre-ranks N,... | --no-hypre]\n";
    return 0;
  }
  Device& dev = Device::current();
  Eigen::setNbThreads(int(std::max(1u, std::thread::hardware_concurrency())));
  if (o.eigen_threads.empty()) {
    o.eigen_threads = {Eigen::nbThreads()};
    if (Eigen::nbThreads() > 1) o.eigen_threads.push_back(1);
  }
  std::cerr << "device: " << dev.name() << "; Eigen threads: " << Eigen::nbThreads()
            << "; load average: " << loadavg() << "\n";
  Json out = Json::object();
  out["machine"] = machine_name();
  out["device"] = dev.name();
  out["load_average_start"] = loadavg();
  out["repeats"] = o.repeats;
  out["tolerance"] = kTolerance;
  out["eigen_threads"] = Eigen::nbThreads();

  const Triad triad = measure_triad(dev);
  out["triad_gbs"] = triad.device_gbs;
  out["host_triad_gbs"] = triad.host_gbs;
  std::cerr << "triad: device " << triad.device_gbs << " GB/s, host " << triad.host_gbs << " GB/s\n";

  std::string viennacl_status = viennacl_start_status(dev, o.use_viennacl);
  const std::string hypre = o.hypre_ranks == std::vector<int>{0} ? std::string("not run") : hypre_status();
  if (o.hypre_ranks.empty()) o.hypre_ranks = default_hypre_ranks();
  std::cerr << "hypre: " << hypre << "\n";
  std::vector<Run> runs;
  std::vector<std::string> sources;
  for (long tets : o.sizes) sources.push_back("ellipsoid:" + std::to_string(tets));
  sources.insert(sources.end(), o.meshes.begin(), o.meshes.end());
  for (const std::string& source : sources)
    for (Run& r : run_size(dev, source, o, triad, viennacl_status, hypre)) runs.push_back(std::move(r));

  print_table(runs);
  add_runs(out, runs);
  out["viennacl"] = viennacl_status;
  out["hypre"] = hypre;
  out["load_average_end"] = loadavg();
  const Json ratios = speedups(runs);
  out["speedups"] = ratios;
  std::printf("\nViennaCL: %s\nhypre: %s\n", viennacl_status.c_str(), hypre.c_str());
  for (size_t i = 0; i < ratios.size(); ++i) std::printf("%s\n", ratios.at(i).dump(-1).c_str());
  write_json_file(o.json_path, out);
  std::printf("wrote %s\n", o.json_path.c_str());
  return 0;
} catch (const InputError& e) {
  std::cerr << "vpm_bench_solver: " << e.what() << "\n";
  return 2;
} catch (const NumericalError& e) {
  std::cerr << "vpm_bench_solver: " << e.what() << "\n";
  return 3;
} catch (const std::exception& e) {
  std::cerr << "vpm_bench_solver: " << e.what() << "\n";
  return 1;
}
