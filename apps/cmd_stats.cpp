// vpm stats MESH [--against REF] [--report R.json] [--quiet]
// Reads and validates MESH and prints its size, topology, quality and volume. With --against,
// MESH is a mapped mesh and REF the input it was mapped from (same tets): REF is validated,
// MESH must have the same tets, and the distortion metrics of DESIGN.md section 5 are printed.
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
#include "vpm/metrics.hpp"
#include "vpm/topology.hpp"
#include "vpm/validate.hpp"
#include "vpm/format.hpp"

namespace {

struct MeshStats {
  int vertices = 0, tets = 0, boundary_faces = 0, edges = 0, faces = 0;
  int euler = 0;           // V - E + F - T of the tet complex (1 for a ball)
  int boundary_euler = 0;  // of the boundary surface (2 for a sphere)
  double min_dihedral = 0;
  int min_dihedral_tet = -1;
  double volume = 0;
  int reoriented = 0;
};

MeshStats mesh_stats(const vpm::TetMesh& m) {
  MeshStats s;
  s.vertices = m.num_vertices();
  s.tets = m.num_tets();
  const vpm::Triangles bf = vpm::boundary_faces(m.tets);
  s.boundary_faces = static_cast<int>(bf.rows());
  s.edges = static_cast<int>(vpm::unique_edges(m.tets).rows());
  // Every interior face is shared by two tets, every boundary face belongs to one
  // (faces shared by more than two tets are rejected by validation).
  s.faces = (4 * s.tets + s.boundary_faces) / 2;
  s.euler = s.vertices - s.edges + s.faces - s.tets;
  s.boundary_euler = vpm::surface_topology(s.vertices, bf).euler;
  if (s.tets > 0) {
    const auto angles = vpm::dihedral_angles_deg(m.vertices, m.tets);
    Eigen::Index r = 0, c = 0;
    s.min_dihedral = angles.minCoeff(&r, &c);
    s.min_dihedral_tet = static_cast<int>(r);
  }
  s.volume = vpm::tet_volumes(m.vertices, m.tets).sum();
  return s;
}


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
  MeshStats st;
  std::optional<vpm::MapMetrics> metrics;
  if (against) {
    ref = vpm::read_mesh(*against);
    const vpm::Tets as_read = ref.tets;
    vpm::ValidateOptions opt;
    opt.require_ball_topology = false;
    vpm::validate_mesh(ref, *against, opt);
    if (mesh.num_vertices() != ref.num_vertices())
      throw vpm::InputError(path + ": has " + std::to_string(mesh.num_vertices()) +
                            " vertices but " + *against + " has " +
                            std::to_string(ref.num_vertices()) + " (not a map of it)");
    if (mesh.num_tets() != ref.num_tets())
      throw vpm::InputError(path + ": has " + std::to_string(mesh.num_tets()) + " tets but " +
                            *against + " has " + std::to_string(ref.num_tets()) +
                            " (not a map of it)");
    for (int t = 0; t < mesh.num_tets(); ++t)
      if (mesh.tets.row(t) != as_read.row(t) && mesh.tets.row(t) != ref.tets.row(t))
        throw vpm::InputError(path + ": tet " + std::to_string(t) + " differs from tet " +
                              std::to_string(t) + " of " + *against +
                              " (--against needs the same tets)");
    for (Eigen::Index i = 0; i < mesh.vertices.size(); ++i)
      if (!std::isfinite(mesh.vertices.data()[i]))
        throw vpm::InputError(path + ": vertex " + std::to_string(i / 3) +
                              ": non-finite coordinate");
    mesh.tets = ref.tets;  // orientation taken from the input
    st = mesh_stats(mesh);
    metrics = vpm::map_metrics(vpm::Device::current(), ref.vertices, mesh.vertices, ref.tets);
  } else {
    vpm::ValidateOptions opt;
    opt.require_ball_topology = false;
    const vpm::ValidationReport rep = vpm::validate_mesh(mesh, path, opt);
    st = mesh_stats(mesh);
    st.reoriented = rep.reoriented_tets;
  }

  if (!quiet) {
    std::ostringstream out;
    out << "mesh                " << path << '\n'
        << "vertices            " << st.vertices << '\n'
        << "tets                " << st.tets << '\n'
        << "boundary faces      " << st.boundary_faces << '\n'
        << "euler (V-E+F-T)     " << st.euler << "  (1 for a ball)\n"
        << "boundary euler      " << st.boundary_euler << "  (2 for a sphere)\n"
        << "min dihedral angle  " << vpm::format_sig(st.min_dihedral, 6) << " deg at tet " << st.min_dihedral_tet
        << '\n'
        << "total volume        " << vpm::format_sig(st.volume, 6) << '\n';
    if (!against) out << "reoriented tets     " << st.reoriented << '\n';
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
    vpm::Json& m = j["mesh"];
    m["path"] = path;
    m["vertices"] = st.vertices;
    m["tets"] = st.tets;
    m["boundary_faces"] = st.boundary_faces;
    m["euler"] = st.euler;
    m["boundary_euler"] = st.boundary_euler;
    m["min_dihedral_deg"] = st.min_dihedral;
    m["min_dihedral_tet"] = st.min_dihedral_tet;
    m["volume"] = st.volume;
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
