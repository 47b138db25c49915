#include "vpm/ball_map.hpp"

#include <algorithm>
#include <cstdio>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"
#include "vpm/memory.hpp"

namespace vpm {

namespace {


std::string quality(const ValidationReport& v) {
  char q[160];
  std::snprintf(q, sizeof q, " (input quality: smallest dihedral angle %.3g deg at tet %d)",
                v.min_dihedral_deg, v.min_dihedral_tet);
  return q;
}
}  // namespace

// Measured peaks (docs/robustness.md, "Limits"; 2-core AMD EPYC VM, 2026-11-27), PoCL's being
// the larger at every size: 121 MB at 10k tets, 218 MB at 120k, 480 MB at 383k, 1.11 GB at 1.1M
// (902 bytes a tet over 120 MB fits these within 15 MB), 1.33-1.47 GB at 1.1M and 2.53 GB at
// 2.18M with AMG (from 600k tets on CPUs: 1,160-1,200 bytes a tet), 8.9 GB at 9.85M
// (docs/volume_map.md); a cold PoCL kernel cache adds 145 MB. The line below lies above every
// one of them (by 5 % at 1.1M, 7 % at 2.18M, 30 % at 10M).
constexpr double kMapBaseBytes = 270e6;
constexpr double kMapBytesPerTet = 1150;

double map_memory_estimate(long long tets) { return kMapBaseBytes + kMapBytesPerTet * double(std::max(0LL, tets)); }

void require_map_memory(long long tets, const std::string& source) {
  require_memory(map_memory_estimate(tets), source,
                 "vpm map on " + std::to_string(tets) + " tets: " + format_bytes(kMapBaseBytes) + " + " +
                     format_sig(kMapBytesPerTet, 4) + " bytes a tet");
}

BallMap map_to_ball(Device& device, const TetMesh& input, const ValidationReport& validation,
                    const std::string& source, const BallMapOptions& options) {
  require_map_memory(input.num_tets(), source);
  const auto t_start = Clock::now();
  const auto say = [&](const std::string& line) {
    if (options.volume.progress) options.volume.progress(line);
  };
  BallMap out;
  auto t0 = Clock::now();
  InitialMapOptions io = options.initial;
  if (options.deadline.set()) io.deadline = options.deadline;
  if (!io.progress) io.progress = options.volume.progress;
  InitialMapResult im = initial_map(device, input, io);  // its errors name the quality
  out.timings.initial_map = seconds_since(t0);
  out.initial = im.report.metrics;  // the initial map measured its result already
  say("initial map: vertex mean |r-1| " + pct(out.initial.vertex_volume_ratio.mean_abs_dev) + ", tet " +
      pct(out.initial.tet_volume_ratio.mean_abs_dev) + ", " + std::to_string(out.initial.inverted_tets) +
      " folds");

  Points ball = im.ball;
  if (options.volume.rounds != 0) {
    t0 = Clock::now();
    try {
      VolumeMapOptions vo = options.volume;
      if (options.deadline.set()) vo.deadline = options.deadline;
      vo.poisson = std::move(im.poisson);  // the harmonic step's solver: its pattern is built
      out.volume_map = options.peer ? volume_map_peer(device, im.mesh.vertices, im.mesh.tets, ball, vo, *options.peer)
                                : volume_preserving_map(device, im.mesh.vertices, im.mesh.tets, ball, vo);
    } catch (const NumericalError& e) {
      throw NumericalError(source + ": " + e.what() + quality(validation) + "; nothing written");
    }
    out.timings.volume_map = seconds_since(t0);
  }
  t0 = Clock::now();
  out.final = map_metrics(device, im.mesh.vertices, ball, im.mesh.tets, &im.boundary);
  out.timings.metrics = seconds_since(t0);
  if (out.final.inverted_tets > 0)  // never hand on a folded map
    throw NumericalError(source + ": the map has " + std::to_string(out.final.inverted_tets) +
                         " inverted tets; nothing written (vertex mean |r-1| reached " +
                         pct(out.final.vertex_volume_ratio.mean_abs_dev) + ")" + quality(validation));

  out.mesh.vertices = ball;
  out.mesh.tets = im.mesh.tets;
  out.mesh.point_data = im.mesh.point_data;
  out.mesh.cell_data = im.mesh.cell_data;
  if (!out.mesh.find_point_field("original_position"))
    out.mesh.set_point_field("original_position", im.mesh.vertices);
  out.mesh.set_point_field("vertex_volume_ratio", out.final.vertex_ratio);
  out.mesh.set_cell_field("tet_volume_ratio", out.final.tet_ratio);
  out.device = device.name();
  out.input_vertices = input.num_vertices();
  out.input_tets = input.num_tets();
  out.input_min_dihedral_deg = validation.min_dihedral_deg;
  out.input_reoriented_tets = validation.reoriented_tets;
  out.input_sliver_tets = validation.sliver_tets;
  out.refined_vertices = im.mesh.num_vertices();
  out.refined_tets = im.mesh.num_tets();
  out.placement.device = device.name();
  out.placement.kind = device.description().kind;
  out.placement.merge(im.report.boundary.placement);
  if (out.volume_map) out.placement.merge(out.volume_map->placement);
  out.initial_map = std::move(im.report);
  out.convergence.tolerance = options.volume.tolerance;
  out.convergence.reached = out.final.vertex_volume_ratio.mean_abs_dev;
  out.convergence.reason = out.volume_map ? out.volume_map->stop_reason : "initial map only";
  out.convergence.checked = options.volume.rounds < 0 || out.convergence.reason == "time_budget";
  out.convergence.converged = !out.convergence.checked || out.convergence.reached <= out.convergence.tolerance;
  out.timings.total = seconds_since(t_start);
  return out;
}

Json to_json(const MapConvergence& c) {
  Json j = Json::object();
  j["checked"] = c.checked;
  j["converged"] = c.converged;
  j["tolerance"] = c.tolerance;
  j["reached"] = c.reached;
  j["reason"] = c.reason;
  return j;
}

Json to_json(const BallMap& b) {
  Json j = Json::object();
  j["device"] = b.device;
  Json jin = Json::object();
  jin["vertices"] = b.input_vertices;
  jin["tets"] = b.input_tets;
  jin["min_dihedral_deg"] = b.input_min_dihedral_deg;
  jin["reoriented_tets"] = b.input_reoriented_tets;
  jin["sliver_tets"] = b.input_sliver_tets;
  j["input"] = jin;
  Json jref = Json::object();
  jref["vertices"] = b.refined_vertices;
  jref["tets"] = b.refined_tets;
  j["refined"] = jref;
  j["initial"] = to_json(b.initial);
  j["final"] = to_json(b.final);
  Json rounds = Json::array();
  Json t = Json::object();
  t["initial_map"] = b.timings.initial_map;
  if (b.volume_map) {
    for (const VolumeMapRound& r : b.volume_map->rounds) rounds.push_back(to_json(r));
    t["volume_map"] = b.timings.volume_map;
    t["volume_map_solve"] = b.volume_map->timings.solve;
    t["volume_map_field"] = b.volume_map->timings.field;
    t["volume_map_advect"] = b.volume_map->timings.advect;
    t["volume_map_untangle"] = b.volume_map->timings.untangle;
  }
  t["metrics"] = b.timings.metrics;
  t["total"] = b.timings.total;
  j["rounds"] = rounds;
  j["timings_s"] = t;
  j["initial_map"] = to_json(b.initial_map);
  if (b.volume_map) j["volume_map"] = to_json(*b.volume_map);
  if (b.convergence.checked) j["converged"] = b.convergence.converged;
  j["convergence"] = to_json(b.convergence);
  j["placement"] = to_json(b.placement);
  return j;
}

}  // namespace vpm
