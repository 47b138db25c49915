#pragma once
// vpm_bench_solver's command line (bench/solver.cpp).
#include <string>
#include <vector>

namespace vpm::bench {

struct SolverBenchOptions {
  std::vector<long> sizes = {25000, 100000, 400000, 1600000};  ///< ellipsoid target tet counts
  std::vector<std::string> meshes;  ///< mesh files run after the ellipsoids (--meshes)
  int repeats = 5;
  std::string json_path = "solver.json";
  bool use_viennacl = true, use_eigen = true, use_amg = true;
  std::vector<int> eigen_threads;  ///< empty: all hardware threads and 1
  std::vector<int> hypre_ranks;    ///< empty: 1 and the hardware threads; {0}: no hypre
  bool help = false;
};

/// Parses the arguments; InputError on an unknown one or a missing value.
SolverBenchOptions parse_solver_bench_options(int argc, char** argv);

}  // namespace vpm::bench
