// vpm initial-map MESH -o OUT: the fold-free initial map to the unit ball only (the first
// stage of `vpm map`), for inspection and for users who run their own volume correction.
#include <cstdio>

#include "cli.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/format.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/validate.hpp"

namespace {

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  const vpm::cli::MeshInOut io = vpm::cli::mesh_in_out(args, self);
  const std::string& in = io.in;
  vpm::InitialMapOptions opt;
  const std::string u = args.get("--untangle", "if-folded");
  if (u == "never") opt.untangle = vpm::InitialMapOptions::Untangle::Never;
  else if (u == "if-folded") opt.untangle = vpm::InitialMapOptions::Untangle::IfFolded;
  else if (u == "always") opt.untangle = vpm::InitialMapOptions::Untangle::Always;
  else throw vpm::InputError("option --untangle: '" + u + "' is not one of never, if-folded, always");
  opt.area_correction = args.has("--area-correction");
  opt.sphere_density = vpm::cli::parse_option(
      "--sphere", [&] { return vpm::parse_sphere_density(args.get("--sphere", "area")); });
  opt.sphere_start = vpm::cli::parse_option(
      "--sphere-start", [&] { return vpm::parse_sphere_start(args.get("--sphere-start", "auto")); });
  opt.density_solve = vpm::cli::parse_option(
      "--sphere-solve", [&] { return vpm::parse_density_solve(args.get("--sphere-solve", "auto")); });
  opt.split_edges = !args.has("--no-split");
  const auto report_path = args.get("--report");

  vpm::Device& dev = vpm::Device::current();
  vpm::TetMesh mesh = vpm::read_mesh(in);
  vpm::require_map_memory(mesh.num_tets(), in);  // the initial map is part of the map: an upper bound
  const vpm::ValidationReport vr = vpm::validate_mesh(mesh, in);
  vpm::cli::progress("read " + in + ": " + std::to_string(mesh.num_vertices()) + " vertices, " +
                     std::to_string(mesh.num_tets()) + " tets, smallest dihedral angle " +
                     std::to_string(vr.min_dihedral_deg) + " deg");
  const vpm::InitialMapResult im = vpm::initial_map(dev, mesh, opt);
  const vpm::MapMetrics mm = vpm::map_metrics(dev, im.mesh.vertices, im.ball, im.mesh.tets);

  vpm::TetMesh outm;
  outm.vertices = im.ball;
  outm.tets = im.mesh.tets;
  outm.point_data = im.mesh.point_data;  // includes original_position
  outm.cell_data = im.mesh.cell_data;
  outm.set_point_field("vertex_volume_ratio", mm.vertex_ratio);
  outm.set_cell_field("tet_volume_ratio", mm.tet_ratio);
  vpm::write_mesh(io.out, outm);
  vpm::cli::info("wrote " + io.out + ": " + std::to_string(outm.num_vertices()) + " vertices, " +
                 std::to_string(outm.num_tets()) + " tets; vertex mean |r-1| " +
                 vpm::pct(mm.vertex_volume_ratio.mean_abs_dev) + ", tet " + vpm::pct(mm.tet_volume_ratio.mean_abs_dev) +
                 ", harmonic folds " + std::to_string(im.report.folds_before_untangle) + " -> 0");
  if (report_path) {
    vpm::Json j = vpm::to_json(im.report);
    j["input"]["reoriented_tets"] = vr.reoriented_tets;
    vpm::write_json_file(*report_path, j);
  }
  return 0;
}

vpm::cli::Registrar reg({"initial-map", "MESH -o OUT", "the fold-free initial map to the unit ball (paper 4.1)",
                         {{"--untangle", "never|if-folded|always", "untangle the harmonic map (default if-folded)"},
                          {"--sphere", "area|conformal", "boundary map to the sphere: equal-area (default) or conformal only"},
                          {"--sphere-start", "auto|progressive|axial", "start of the sphere map: conformal, or where it flips or stays crowded the better of progressive and axial (auto, default); progressive; axial"},
                          {"--sphere-solve", "auto|host|device", "the sphere map's equal-area solves: host Cholesky, device AMG-CG, or auto (default: a GPU from 50,000 boundary vertices)"},
                          {"--area-correction", "", "equalise areas on the sphere before the interior map"},
                          {"--no-split", "", "do not split interior edges between boundary vertices"},
                          {"--report", "REPORT.json", "write the report (stages, metrics, timings)"}},
                         run});
}  // namespace
