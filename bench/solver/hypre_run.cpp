#include "solver/hypre_run.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <thread>

#include "vpm/error.hpp"
#include "vpm/json.hpp"

namespace vpm::bench {

namespace fs = std::filesystem;

namespace {

fs::path hypre_program() { return fs::read_symlink("/proc/self/exe").parent_path() / "vpm_bench_hypre"; }

bool mpirun_on_path() { return std::system("command -v mpirun > /dev/null 2>&1") == 0; }

}  // namespace

std::vector<int> default_hypre_ranks() {
  const int threads = static_cast<int>(std::thread::hardware_concurrency());
  return threads > 1 ? std::vector<int>{1, threads} : std::vector<int>{1};
}

std::string hypre_status() {
  if (!fs::exists(hypre_program()))
    return "not built (hypre or MPI not found at configure time; scripts/setup.sh installs libhypre-dev)";
  if (!mpirun_on_path()) return "mpirun not on PATH";
  return "ok";
}

HypreRun run_hypre(const std::string& source, int ranks, int repeats, long vertices, long nnz) {
  const fs::path json = fs::temp_directory_path() / ("vpm_bench_hypre_" + std::to_string(getpid()) + ".json");
  // OpenMPI refuses root unless told; the benchmark may run as root in a container
  const std::string root = geteuid() == 0 ? " --allow-run-as-root" : "";
  const std::string cmd = "mpirun" + root + " -np " + std::to_string(ranks) + " '" + hypre_program().string() +
                          "' --problem '" + source + "' --repeats " + std::to_string(repeats) +
                          " --json '" + json.string() + "'";
  const int rc = std::system(cmd.c_str());
  if (rc != 0 || !fs::exists(json)) {
    fs::remove(json);
    throw NumericalError("hypre peer failed (status " + std::to_string(rc) + "): " + cmd);
  }
  const Json j = read_json_file(json.string());
  fs::remove(json);
  if (long(j.find("vertices")->number()) != vertices || long(j.find("nnz")->number()) != nnz)
    throw NumericalError("vpm_bench_hypre built a different problem: " + cmd);
  HypreRun h;
  const Json &solve = *j.find("times_s"), &setup = *j.find("setup_times_s");
  for (size_t k = 0; k < solve.size(); ++k) h.solve_s.push_back(solve.at(k).number());
  for (size_t k = 0; k < setup.size(); ++k) h.setup_s.push_back(setup.at(k).number());
  if (h.solve_s.empty() || h.setup_s.size() != h.solve_s.size())
    throw NumericalError("vpm_bench_hypre wrote no timings: " + cmd);
  h.iterations = static_cast<int>(j.find("iterations")->number());
  h.relative_residual = j.find("relative_residual")->number();
  h.settings = j.find("settings")->string();
  return h;
}

}  // namespace vpm::bench
