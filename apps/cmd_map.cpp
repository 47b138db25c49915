// vpm map MESH -o OUT: initial map to the unit ball, then the volume-preserving map.
#include <chrono>
#include <cstdio>

#include "cli.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/validate.hpp"
#include "vpm/volume_map.hpp"

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

const char* kUsage =
    "vpm map MESH -o OUT [--rounds R] [--tolerance T] [--method moser|paper|vsem] "
    "[--boundary slide|fixed] [--solver cg|paper] [--rk-steps N] [--report REPORT.json] "
    "[--quiet] [--verbose]";

std::string pct(double x) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f %%", 100 * x);
  return b;
}

int run(const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv,
                      {"--rounds", "--tolerance", "--method", "--boundary", "--solver", "--report",
                       "--rk-steps"},
                      {});
  args.expect_positional(1, kUsage);
  const std::string in = args.positional()[0];
  const auto out = args.get("-o");
  if (!out) throw vpm::InputError(std::string("missing -o OUT; usage: ") + kUsage);
  if (!vpm::is_mesh_path(in)) throw vpm::InputError(in + ": unknown mesh file extension");
  if (!vpm::is_mesh_path(*out)) throw vpm::InputError(*out + ": unknown mesh file extension for the output");

  vpm::VolumeMapOptions vo;
  vo.rounds = args.get_int("--rounds", -1);
  if (vo.rounds < -1) throw vpm::InputError("option --rounds: must be >= 0");
  vo.tolerance = args.get_double("--tolerance", 0.01);
  if (!(vo.tolerance >= 0)) throw vpm::InputError("option --tolerance: must be >= 0");
  vo.method = vpm::parse_volume_map_method(args.get("--method", "moser"));
  vo.boundary = vpm::parse_map_boundary(args.get("--boundary", "auto"));
  vo.solver = args.get("--solver", "cg");
  if (vo.solver != "cg" && vo.solver != "paper")
    throw vpm::InputError("option --solver: '" + vo.solver + "' is not one of cg, paper");
  vo.rk_steps = args.get_int("--rk-steps", 40);
  if (vo.rk_steps < 1) throw vpm::InputError("option --rk-steps: must be >= 1");
  vo.progress = [](const std::string& line) { vpm::cli::progress(line); };
  const auto report_path = args.get("--report");

  const auto t_start = Clock::now();
  vpm::Device& dev = vpm::Device::current();
  vpm::Json timings = vpm::Json::object();

  auto t0 = Clock::now();
  vpm::TetMesh mesh = vpm::read_mesh(in);
  const vpm::ValidationReport vr = vpm::validate_mesh(mesh, in);
  timings["read"] = since(t0);
  vpm::cli::progress("read " + in + ": " + std::to_string(mesh.num_vertices()) + " vertices, " +
                     std::to_string(mesh.num_tets()) + " tets");

  t0 = Clock::now();
  vpm::InitialMapResult im = vpm::initial_map(dev, mesh);
  timings["initial_map"] = since(t0);
  const vpm::MapMetrics m0 = vpm::map_metrics(dev, im.mesh.vertices, im.ball, im.mesh.tets);
  vpm::cli::progress("initial map: vertex mean |r-1| " + pct(m0.vertex_volume_ratio.mean_abs_dev) +
                     ", tet " + pct(m0.tet_volume_ratio.mean_abs_dev) + ", " +
                     std::to_string(m0.inverted_tets) + " folds");

  vpm::Points ball = im.ball;
  vpm::Json vm_report;
  vpm::Json rounds = vpm::Json::array();
  if (vo.rounds != 0) {
    t0 = Clock::now();
    vpm::VolumeMapResult vm;
    try {
      vm = vpm::volume_preserving_map(dev, im.mesh.vertices, im.mesh.tets, ball, vo);
    } catch (const vpm::NumericalError& e) {
      char q[160];
      std::snprintf(q, sizeof q, " (input quality: smallest dihedral angle %.3g deg at tet %d)",
                    vr.min_dihedral_deg, vr.min_dihedral_tet);
      throw vpm::NumericalError(in + ": " + e.what() + q + "; nothing written");
    }
    timings["volume_map"] = since(t0);
    vm_report = vm.report;
    if (const vpm::Json* r = vm.report.find("rounds")) rounds = *r;
    if (const vpm::Json* t = vm.report.find("timings_s")) {
      for (const char* k : {"solve", "field", "advect", "untangle"})
        if (const vpm::Json* v = t->find(k)) timings[std::string("volume_map_") + k] = *v;
    }
  }
  const vpm::MapMetrics m1 = vpm::map_metrics(dev, im.mesh.vertices, ball, im.mesh.tets);
  if (m1.inverted_tets > 0)  // never write a folded map
    throw vpm::NumericalError(in + ": the map has " + std::to_string(m1.inverted_tets) +
                              " inverted tets; nothing written (vertex mean |r-1| reached " +
                              pct(m1.vertex_volume_ratio.mean_abs_dev) + ")");

  // Output: ball positions, refined tets, input fields carried, ratios and original positions.
  t0 = Clock::now();
  vpm::TetMesh outm;
  outm.vertices = ball;
  outm.tets = im.mesh.tets;
  outm.point_data = im.mesh.point_data;
  outm.cell_data = im.mesh.cell_data;
  if (!outm.find_point_field("original_position")) outm.set_point_field("original_position", im.mesh.vertices);
  outm.set_point_field("vertex_volume_ratio", m1.vertex_ratio);
  outm.set_cell_field("tet_volume_ratio", m1.tet_ratio);
  vpm::write_mesh(*out, outm);
  timings["write"] = since(t0);
  timings["total"] = since(t_start);

  vpm::cli::info("wrote " + *out + ": " + std::to_string(outm.num_vertices()) + " vertices, " +
                 std::to_string(outm.num_tets()) + " tets; vertex mean |r-1| " +
                 pct(m0.vertex_volume_ratio.mean_abs_dev) + " -> " +
                 pct(m1.vertex_volume_ratio.mean_abs_dev) + ", tet " +
                 pct(m0.tet_volume_ratio.mean_abs_dev) + " -> " + pct(m1.tet_volume_ratio.mean_abs_dev) +
                 ", 0 folds");

  if (report_path) {
    vpm::Json j = vpm::Json::object();
    j["device"] = dev.name();
    vpm::Json jin = vpm::Json::object();
    jin["vertices"] = mesh.num_vertices();
    jin["tets"] = mesh.num_tets();
    jin["min_dihedral_deg"] = vr.min_dihedral_deg;
    jin["reoriented_tets"] = vr.reoriented_tets;
    j["input"] = jin;
    vpm::Json jref = vpm::Json::object();
    jref["vertices"] = im.mesh.num_vertices();
    jref["tets"] = im.mesh.num_tets();
    j["refined"] = jref;
    j["initial"] = vpm::to_json(m0);
    j["final"] = vpm::to_json(m1);
    j["rounds"] = rounds;
    j["timings_s"] = timings;
    j["initial_map"] = im.report;
    if (vo.rounds != 0) j["volume_map"] = vm_report;
    vpm::write_json_file(*report_path, j);
  }
  return 0;
}

vpm::cli::Registrar reg({"map", kUsage, run});
}  // namespace
