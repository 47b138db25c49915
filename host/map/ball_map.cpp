#include "vpm/ball_map.hpp"

#include <chrono>
#include <cstdio>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"

namespace vpm {

namespace {


std::string quality(const ValidationReport& v) {
  char q[160];
  std::snprintf(q, sizeof q, " (input quality: smallest dihedral angle %.3g deg at tet %d)",
                v.min_dihedral_deg, v.min_dihedral_tet);
  return q;
}
}  // namespace

BallMap map_to_ball(Device& device, const TetMesh& input, const ValidationReport& validation,
                    const std::string& source, const BallMapOptions& options) {
  const auto t_start = Clock::now();
  Json timings = Json::object();
  const auto say = [&](const std::string& line) {
    if (options.volume.progress) options.volume.progress(line);
  };

  auto t0 = Clock::now();
  InitialMapResult im = initial_map(device, input, options.initial);  // its errors name the quality
  timings["initial_map"] = seconds_since(t0);
  BallMap out;
  out.initial = map_metrics(device, im.mesh.vertices, im.ball, im.mesh.tets);
  say("initial map: vertex mean |r-1| " + pct(out.initial.vertex_volume_ratio.mean_abs_dev) + ", tet " +
      pct(out.initial.tet_volume_ratio.mean_abs_dev) + ", " + std::to_string(out.initial.inverted_tets) +
      " folds");

  Points ball = im.ball;
  Json vm_report;
  Json rounds = Json::array();
  if (options.volume.rounds != 0) {
    t0 = Clock::now();
    VolumeMapResult vm;
    try {
      vm = volume_preserving_map(device, im.mesh.vertices, im.mesh.tets, ball, options.volume);
    } catch (const NumericalError& e) {
      throw NumericalError(source + ": " + e.what() + quality(validation) + "; nothing written");
    }
    timings["volume_map"] = seconds_since(t0);
    vm_report = vm.report;
    if (const Json* r = vm.report.find("rounds")) rounds = *r;
    if (const Json* t = vm.report.find("timings_s"))
      for (const char* k : {"solve", "field", "advect", "untangle"})
        if (const Json* v = t->find(k)) timings[std::string("volume_map_") + k] = *v;
  }
  t0 = Clock::now();
  out.final = map_metrics(device, im.mesh.vertices, ball, im.mesh.tets);
  timings["metrics"] = seconds_since(t0);
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
  timings["total"] = seconds_since(t_start);

  Json& j = out.report = Json::object();
  j["device"] = device.name();
  Json jin = Json::object();
  jin["vertices"] = input.num_vertices();
  jin["tets"] = input.num_tets();
  jin["min_dihedral_deg"] = validation.min_dihedral_deg;
  jin["reoriented_tets"] = validation.reoriented_tets;
  j["input"] = jin;
  Json jref = Json::object();
  jref["vertices"] = im.mesh.num_vertices();
  jref["tets"] = im.mesh.num_tets();
  j["refined"] = jref;
  j["initial"] = to_json(out.initial);
  j["final"] = to_json(out.final);
  j["rounds"] = rounds;
  j["timings_s"] = timings;
  j["initial_map"] = im.report;
  if (options.volume.rounds != 0) j["volume_map"] = vm_report;
  return out;
}

}  // namespace vpm
