// vpm map MESH -o OUT: initial map to the unit ball, then the volume-preserving map; a closed
// triangle surface instead goes to the unit sphere with its areas kept (map_surface.cpp).
#include <chrono>
#include <cstdio>

#include <optional>

#include "cli.hpp"
#include "map_surface.hpp"
#include "vpm/volume_map_peers.hpp"
#include "vpm/format.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/solver.hpp"
#include "vpm/validate.hpp"
#include "vpm/timing.hpp"

namespace {

using vpm::Clock;
using vpm::seconds_since;


int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  const auto t_start = Clock::now();
  vpm::cli::Args args(argv, self);
  // a triangle surface goes to the sphere (apps/map_surface.cpp)
  if (args.positional().size() == 1 && !vpm::is_mesh_path(args.positional()[0]) &&
      vpm::is_surface_path(args.positional()[0])) {
    const auto out = args.get("-o");
    if (!out) throw vpm::InputError("missing -o OUT; usage: " + vpm::cli::synopsis(self));
    return vpm::cli::map_surface(args, args.positional()[0], *out, t_start);
  }
  const vpm::cli::MeshInOut io = vpm::cli::mesh_in_out(args, self);
  if (args.has("--overlays")) throw vpm::InputError("option --overlays: applies to surfaces only; " + io.in + " is a tet mesh");
  const std::string& in = io.in;

  vpm::VolumeMapOptions vo;
  vo.rounds = args.get_int("--rounds", -1);
  if (vo.rounds < -1) throw vpm::InputError("option --rounds: must be >= 0");
  vo.tolerance = args.get_double("--tolerance", 0.01);
  if (!(vo.tolerance >= 0)) throw vpm::InputError("option --tolerance: must be >= 0");
  const std::string method = args.get("--method", "moser");  // moser, or a peer (shared/DESIGN.md's contract)
  std::optional<vpm::VolumeMapPeerOptions> peer;
  if (method != "moser")
    peer = vpm::VolumeMapPeerOptions{vpm::cli::parse_option("--method", [&] { return vpm::parse_volume_map_peer(method); })};
  const std::string solver = args.get("--solver", "cg");
  if (solver != "cg" && solver != "paper")
    throw vpm::InputError("option --solver: '" + solver + "' is not one of cg, paper");
  vo.solver = vpm::parse_solver_method(solver);
  vo.boundary = vpm::cli::parse_option("--boundary", [&] { return vpm::parse_map_boundary(args.get("--boundary", "auto")); });
  vo.preconditioner = vpm::cli::parse_option(
      "--preconditioner", [&] { return vpm::parse_preconditioner_choice(args.get("--preconditioner", "auto")); });
  vo.rk_steps = args.get_int("--rk-steps", vo.rk_steps);
  if (vo.rk_steps < 1) throw vpm::InputError("option --rk-steps: must be >= 1");
  vo.progress = [](const std::string& line) { vpm::cli::progress(line); };
  const auto report_path = args.get("--report");

  vpm::Device& dev = vpm::Device::current();
  auto t0 = Clock::now();
  vpm::TetMesh mesh = vpm::read_mesh(in);
  vpm::require_map_memory(mesh.num_tets(), in);  // before validation: refuse what cannot fit up front
  const vpm::ValidationReport vr = vpm::validate_mesh(mesh, in);
  const double t_read = seconds_since(t0);
  vpm::cli::progress("read " + in + ": " + std::to_string(mesh.num_vertices()) + " vertices, " +
                     std::to_string(mesh.num_tets()) + " tets");

  if (vr.sliver_tets > 0)
    std::fprintf(stderr,
                 "vpm map: warning: %s: %d tets with a dihedral angle below %g deg (smallest %.3g deg at tet %d): "
                 "slivers can make the map fold or stall; remesh first: vpm convert %s boundary.off && "
                 "vpm mesh-image boundary.off -o remeshed.vtu\n",
                 in.c_str(), vr.sliver_tets, vpm::kSliverDihedralDeg, vr.min_dihedral_deg, vr.min_dihedral_tet, in.c_str());
  vpm::BallMapOptions bo;
  bo.volume = vo;
  bo.peer = peer;
  bo.deadline = vpm::cli::time_budget(args, t_start);
  bo.initial.preconditioner = vo.preconditioner;
  bo.initial.sphere_density = vpm::cli::parse_option(
      "--sphere", [&] { return vpm::parse_sphere_density(args.get("--sphere", "area")); });
  bo.initial.sphere_start = vpm::cli::parse_option(
      "--sphere-start", [&] { return vpm::parse_sphere_start(args.get("--sphere-start", "auto")); });
  bo.initial.density_solve = vpm::cli::parse_option(
      "--sphere-solve", [&] { return vpm::parse_density_solve(args.get("--sphere-solve", "auto")); });
  vpm::BallMap bm = vpm::map_to_ball(dev, mesh, vr, in, bo);

  t0 = Clock::now();
  vpm::write_mesh(io.out, bm.mesh);
  vpm::Json report = vpm::to_json(bm);
  vpm::Json& timings = report["timings_s"];
  timings["read"] = t_read;
  timings["write"] = seconds_since(t0);
  timings["total"] = seconds_since(t_start);

  vpm::cli::info("wrote " + io.out + ": " + std::to_string(bm.mesh.num_vertices()) + " vertices, " +
                 std::to_string(bm.mesh.num_tets()) + " tets; vertex mean |r-1| " +
                 vpm::pct(bm.initial.vertex_volume_ratio.mean_abs_dev) + " -> " +
                 vpm::pct(bm.final.vertex_volume_ratio.mean_abs_dev) + ", tet " +
                 vpm::pct(bm.initial.tet_volume_ratio.mean_abs_dev) + " -> " +
                 vpm::pct(bm.final.tet_volume_ratio.mean_abs_dev) + ", 0 folds");
  if (report_path) vpm::write_json_file(*report_path, report);
  return vpm::cli::convergence_status("map", bm.convergence, args.has("--allow-partial"));
}

vpm::cli::Registrar reg(vpm::cli::with_expert({"map", "MESH|SURFACE -o OUT", "map a tet mesh to the unit ball preserving local volumes, or a surface to the unit sphere (closed) or disk (one boundary loop) preserving local areas",
                         {{"--rounds", "R", "Moser rounds (default: until --tolerance, at most 8; 0: the initial map only); surfaces: polish steps (default 200)"},
                          {"--tolerance", "T", "stop at this vertex mean |r-1| (default 0.01; surfaces: face area mean |r-1|, default 0.005); missing it warns, by over 2x exits 4"},
                          {"--allow-partial", "", "exit 0 even when the map misses --tolerance by over 2x (the warning stays)"},
                          {"--method", "moser|paper|vsem", "moser (default) or a peer method for comparison"},
                          {"--sphere", "area|conformal", "boundary map to the sphere: equal-area (default) or conformal only"},
                          {"--sphere-start", "auto|progressive|axial", "start of the sphere map: conformal, or where it flips or stays crowded the better of progressive and axial (auto, default); progressive; axial"},
                          {"--sphere-solve", "auto|host|device", "the sphere map's equal-area solves: host Cholesky, device AMG-CG, or auto (default: a GPU from 50,000 boundary vertices)"},
                          {"--boundary", "slide|fixed", "boundary vertices slide on the sphere (moser default) or stay"},
                          {"--solver", "cg|paper", "Jacobi CG (default) or the paper's BiCGSTAB on the normal equations"},
                          {"--preconditioner", "auto|jacobi|amg", "of CG: Jacobi, smoothed-aggregation AMG, or auto (default: AMG on CPUs from 600k tets)"},
                          {"--rk-steps", "N", "RK4 steps per Moser round (default " + std::to_string(vpm::VolumeMapOptions{}.rk_steps) + ")"},
                          {"--overlays", "A,B", "surfaces: per-vertex files (FreeSurfer lh.curv, lh.thickness; GIfTI .shape.gii) carried to the output's point fields"},
                          {"--max-seconds", "S", "time budget: the rounds stop when it is spent and the map reached is written (exit 4)"},
                          {"--report", "REPORT.json", "write the report (metrics, rounds, timings)"}},
                         run},
    // the peers (shared/DESIGN.md's contract), the solvers' knobs and the sphere map's starts and
    // solves: for experiments and benchmarks
    {"--method", "--solver", "--preconditioner", "--rk-steps", "--sphere-start", "--sphere-solve"}));
}  // namespace
