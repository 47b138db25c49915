// vpm stats MESH [--against REF] [--report R.json] [--quiet]
// Reads and validates MESH and prints its size, topology, quality and volume. With --against,
// MESH is a mapped mesh and REF the input it was mapped from (same tets): REF is validated,
// MESH must have the same tets, and the distortion metrics of docs/design.md 5 are printed.
#include <cmath>
#include <cstdio>
#include <optional>
#include <iostream>
#include <sstream>

#include "cli.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_stats.hpp"
#include "vpm/metrics.hpp"
#include "vpm/topology.hpp"
#include "vpm/validate.hpp"
#include "vpm/format.hpp"

namespace {

void print_ratio(std::ostream& out, const char* name, const vpm::RatioStats& r) {
  out << name << "  mean|r-1| " << vpm::format_sig(r.mean_abs_dev, 6) << "  std log " << vpm::format_sig(r.std_log, 6)
      << "  p99|log| " << vpm::format_sig(r.p99_abs_log, 6) << "  max|log| " << vpm::format_sig(r.max_abs_log, 6) << "  min "
      << vpm::format_sig(r.min, 6) << "  max " << vpm::format_sig(r.max, 6) << '\n';
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  const std::string usage = vpm::cli::synopsis(self);
  args.expect_positional(1, usage);
  const std::string path = args.positional()[0];
  const auto against = args.get("--against");
  const auto report_path = args.get("--report");
  const bool quiet = vpm::cli::verbosity().quiet;

  vpm::TetMesh mesh = vpm::read_mesh(path);
  vpm::TetMesh ref;
  vpm::ValidateOptions opt;
  opt.require_ball_topology = false;
  int reoriented = 0;
  std::optional<vpm::MapMetrics> metrics;
  if (against) {
    ref = vpm::read_mesh(*against);
    const vpm::Tets as_read = ref.tets;
    vpm::validate_mesh(ref, *against, opt);
    vpm::check_map_of(mesh, path, ref, as_read, *against);
    mesh.tets = ref.tets;  // orientation taken from the input
    metrics = vpm::map_metrics(vpm::Device::current(), ref.vertices, mesh.vertices, ref.tets);
  } else {
    reoriented = vpm::validate_mesh(mesh, path, opt).reoriented_tets;
  }
  const vpm::MeshStats st = vpm::mesh_stats(mesh);

  if (!quiet) {
    std::ostringstream out;
    out << "mesh                " << path << '\n'
        << "vertices            " << st.vertices << '\n'
        << "tets                " << st.tets << '\n'
        << "boundary faces      " << st.boundary_faces << '\n'
        << "euler (V-E+F-T)     " << st.euler << "  (1 for a ball)\n"
        << "boundary euler      " << st.boundary_euler << "  (2 for a sphere)\n"
        << "min dihedral angle  " << vpm::format_sig(st.min_dihedral_deg, 6) << " deg at tet " << st.min_dihedral_tet
        << '\n'
        << "total volume        " << vpm::format_sig(st.volume, 6) << '\n';
    if (!against) out << "reoriented tets     " << reoriented << '\n';
    if (metrics) {
      out << "against             " << *against << '\n'
          << "inverted tets       " << metrics->inverted_tets << '\n';
      print_ratio(out, "vertex volume ratio", metrics->vertex_volume_ratio);
      print_ratio(out, "tet volume ratio   ", metrics->tet_volume_ratio);
      out << "boundary max radius error  " << vpm::format_sig(metrics->boundary_max_radius_error, 6) << '\n';
    }
    std::cout << out.str();
  }
  if (report_path) {
    vpm::Json j = vpm::Json::object();
    j["device"] = vpm::Device::current().name();
    const vpm::TetMesh& input = against ? ref : mesh;
    j["input"]["vertices"] = input.num_vertices();
    j["input"]["tets"] = input.num_tets();
    j["mesh"] = vpm::to_json(st);
    j["mesh"]["path"] = path;
    if (metrics) j["metrics"] = vpm::to_json(*metrics);
    vpm::write_json_file(*report_path, j);
  }
  return 0;
}

vpm::cli::Registrar reg({"stats", "MESH", "mesh statistics, and the metrics of a map against its input",
                         {{"--against", "REF", "the input mesh MESH was mapped from: volume ratios, folds"},
                          {"--report", "R.json", "write the statistics as JSON"}},
                         run});
}  // namespace
