#include "solver/options.hpp"

#include <algorithm>
#include <sstream>

#include "vpm/error.hpp"

namespace vpm::bench {

namespace {

std::vector<std::string> text_list(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  for (std::string tok; std::getline(ss, tok, ',');)
    if (!tok.empty()) out.push_back(tok);
  return out;
}

std::vector<long> int_list(const std::string& text) {
  std::vector<long> out;
  for (const std::string& tok : text_list(text)) out.push_back(std::stol(tok));
  return out;
}

}  // namespace

SolverBenchOptions parse_solver_bench_options(int argc, char** argv) {
  SolverBenchOptions o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError(a + ": missing value");
      return argv[++i];
    };
    if (a == "--quick") o.sizes = {25000, 100000};
    else if (a == "--sizes") o.sizes = int_list(next());
    else if (a == "--meshes") o.meshes = text_list(next());
    else if (a == "--repeats") o.repeats = std::max(1, std::stoi(next()));
    else if (a == "--json") o.json_path = next();
    else if (a == "--no-viennacl") o.use_viennacl = false;
    else if (a == "--no-eigen") o.use_eigen = false;
    else if (a == "--no-amg") o.use_amg = false;
    else if (a == "--eigen-threads") o.eigen_threads = {std::max(1, std::stoi(next()))};
    else if (a == "--no-hypre") o.hypre_ranks = {0};
    else if (a == "--hypre-ranks") for (long r : int_list(next())) o.hypre_ranks.push_back(int(std::max(1L, r)));
    else if (a == "-h" || a == "--help") {
      o.help = true;
      return o;
    }
    else throw InputError("unknown argument " + a);
  }
  return o;
}

}  // namespace vpm::bench
