#pragma once
// vpm_bench_solver's side of the hypre peer: finds vpm_bench_hypre next to the running program
// and mpirun on PATH, runs one size under `mpirun -np N`, and returns the JSON it wrote.
#include <string>
#include <vector>

namespace vpm::bench {

// vpm_bench_hypre is built where Debian's libhypre-dev is installed; the solver benchmark runs it
// for each rank count after the other peers of a size (not interleaved with them).

/// The rank counts run by default: 1 and the hardware threads.
std::vector<int> default_hypre_ranks();

/// "ok" when vpm_bench_hypre and mpirun are both there, else why the hypre peer is not run.
std::string hypre_status();

/// What vpm_bench_hypre measured: per repeat the solve and the BoomerAMG setup (seconds).
struct HypreRun {
  std::vector<double> solve_s, setup_s;
  int iterations = 0;
  double relative_residual = 0;  ///< |K x - b| / |b| of the last solve
  std::string settings;          ///< BoomerAMG's settings in words
};

/// Runs vpm_bench_hypre on the problem `source` (bench::problem_mesh) with `ranks` MPI processes
/// and `repeats` timed solves. Throws NumericalError naming the command when it fails, or when
/// its problem is not the caller's (`vertices`, `nnz`).
HypreRun run_hypre(const std::string& source, int ranks, int repeats, long vertices, long nnz);

}  // namespace vpm::bench
