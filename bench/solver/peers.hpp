#pragma once
// The solvers that vpm_bench_solver compares on one problem: vpm's CG on the selected device,
// Eigen's CG on the host and ViennaCL 1.7.1's CG on the same OpenCL device. Each is a Peer:
// a set of functions over its own state, so that the repeats can be interleaved round-robin.
#include <Eigen/Core>
#include <algorithm>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vpm/device.hpp"
#include "vpm/mesh.hpp"
#include "vpm/solver.hpp"
#include "vpm/sparse.hpp"

namespace vpm::bench {

/// The median of repeated timings (the mean of the middle two for an even count).
inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// CG stopping tolerance (relative residual) of every peer.
constexpr double kTolerance = 1e-8;

/// The mesh of a benchmark problem from its source: "ellipsoid:N" (the jittered voxel ellipsoid
/// of about N tets, named ellipsoid-<N/1000>k) or a tet mesh file (named by its file name
/// without the folder). Sets `name`.
TetMesh problem_mesh(const std::string& source, std::string& name);

/// One benchmark problem: the cotangent Laplacian K of a mesh and a zero-mean right-hand side
/// b (normal, seed 42); the peers solve the Neumann problem K x = b.
struct Problem {
  Problem(Device& dev, std::string name, TetMesh mesh);
  std::string name;
  TetMesh mesh;
  int n;
  PoissonSolver solver;  ///< vpm's solver; owns K
  CsrMatrix K;  ///< the Laplacian (a copy of the solver's)
  long nnz;
  Eigen::VectorXd b;
  CsrMatrix::EigenType K_spd;  ///< -K: symmetric positive semi-definite, the same CG iterates
  Eigen::VectorXd b_spd;       ///< -b
};

/// A solver under test. solve_once returns its seconds; iterations and solution refer to the
/// last solve; spmv_seconds times one product with its own matrix kernel.
struct Peer {
  std::string solver;   ///< the `solver` name in the table and JSON
  int threads = 0;      ///< host threads (Eigen only; 0: not reported)
  double triad_gbs = 0; ///< the bandwidth its SpMV is compared with (device or host triad)
  std::function<double()> solve_once;
  std::function<int()> iterations;
  std::function<Eigen::VectorXd()> solution;
  std::function<double()> spmv_seconds;
  /// AMG peers only: the last solve's hierarchy value update (seconds, excluded from
  /// solve_once) and the first full build.
  std::function<double()> setup_update_seconds;
  std::function<double()> setup_build_seconds;
};

/// vpm's CG (PoissonSolver::solve_neumann) and its SpMV kernel alone.
Peer vpm_peer(Device& dev, Problem& p, double triad_gbs);

/// vpm's AMG-preconditioned CG ("vpm-amg-cg" on `dev`, "vpm-amg-cg-host" on the host
/// backend): its own PoissonSolver; each solve first re-sets the positions, so every solve
/// updates the hierarchy's values (timed separately), as in a flow step.
Peer vpm_amg_peer(Device& dev, Problem& p, double triad_gbs, bool host);

/// Eigen's Jacobi-preconditioned CG on -K, one peer per thread count ("eigen-cg", or
/// "eigen-cg-1thread" for 1 thread).
std::vector<Peer> eigen_peers(const Problem& p, const std::vector<int>& thread_counts,
                              double host_triad_gbs);

/// Makes ViennaCL run on the device's OpenCL context and queue. Returns "ok" or why not.
std::string setup_viennacl(Device& dev);

/// ViennaCL's CG on -K after setup_viennacl: "viennacl-cg" (Jacobi-preconditioned, the same
/// algorithm as vpm's) and "viennacl-cg-pipelined-nopc" (unpreconditioned, ViennaCL's
/// pipelined CG with fused kernels). Throws when ViennaCL fails on the problem.
std::vector<Peer> viennacl_peers(const Problem& p, double triad_gbs);

}  // namespace vpm::bench
