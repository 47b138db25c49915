#pragma once
// vpm_bench_solver's side of the hypre peer: finds vpm_bench_hypre next to the running program
// and mpirun on PATH, runs one size under `mpirun -np N`, and returns the JSON it wrote.
#include <string>

#include "vpm/json.hpp"

namespace vpm::bench {

/// "ok" when vpm_bench_hypre and mpirun are both there, else why the hypre peer is not run.
std::string hypre_status();

/// Runs vpm_bench_hypre on the ellipsoid of `target_tets` with `ranks` MPI processes and
/// `repeats` timed solves. Throws NumericalError naming the command when it fails.
Json run_hypre(long target_tets, int ranks, int repeats);

}  // namespace vpm::bench
