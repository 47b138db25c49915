#include "solver/hypre_run.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "vpm/error.hpp"

namespace vpm::bench {

namespace fs = std::filesystem;

namespace {

fs::path hypre_program() { return fs::read_symlink("/proc/self/exe").parent_path() / "vpm_bench_hypre"; }

bool mpirun_on_path() { return std::system("command -v mpirun > /dev/null 2>&1") == 0; }

}  // namespace

std::string hypre_status() {
  if (!fs::exists(hypre_program()))
    return "not built (hypre or MPI not found at configure time; scripts/setup.sh installs libhypre-dev)";
  if (!mpirun_on_path()) return "mpirun not on PATH";
  return "ok";
}

Json run_hypre(long target_tets, int ranks, int repeats) {
  const fs::path json = fs::temp_directory_path() / ("vpm_bench_hypre_" + std::to_string(getpid()) + ".json");
  // OpenMPI refuses root unless told; the benchmark may run as root in a container
  const std::string root = geteuid() == 0 ? " --allow-run-as-root" : "";
  const std::string cmd = "mpirun" + root + " -np " + std::to_string(ranks) + " '" + hypre_program().string() +
                          "' --size " + std::to_string(target_tets) + " --repeats " + std::to_string(repeats) +
                          " --json '" + json.string() + "'";
  const int rc = std::system(cmd.c_str());
  if (rc != 0 || !fs::exists(json)) {
    fs::remove(json);
    throw NumericalError("hypre peer failed (status " + std::to_string(rc) + "): " + cmd);
  }
  Json out = read_json_file(json.string());
  fs::remove(json);
  return out;
}

}  // namespace vpm::bench
