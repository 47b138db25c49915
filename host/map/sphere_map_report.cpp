// The sphere map's options parsed from their names and its report as JSON (vpm/initial_map.hpp).
#include <string>

#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/placement.hpp"

namespace vpm {

InitialMapOptions::SphereDensity parse_sphere_density(const std::string& name) {
  using D = InitialMapOptions::SphereDensity;
  if (name == "conformal") return D::conformal;
  if (name == "area") return D::area;
  throw InputError("sphere density '" + name + "' is not one of conformal, area");
}

InitialMapOptions::DensitySolve parse_density_solve(const std::string& name) {
  return parse_execution_place(name, "sphere solve");
}

InitialMapOptions::SphereStart parse_sphere_start(const std::string& name) {
  using S = InitialMapOptions::SphereStart;
  if (name == "auto") return S::automatic;
  if (name == "progressive") return S::progressive;
  if (name == "axial") return S::axial;
  throw InputError("sphere start '" + name + "' is not one of auto, progressive, axial");
}

const char* to_string(InitialMapOptions::SphereDensity d) {
  using D = InitialMapOptions::SphereDensity;
  return d == D::conformal ? "conformal" : "area";
}

Json to_json(const SphereMapReport& r) {
  Json j = Json::object();
  j["vertices"] = r.vertices;
  j["faces"] = r.faces;
  j["planar_weights"] = r.planar_weights;
  j["flipped_after_conformal"] = r.flipped_after_conformal;
  if (r.flipped_after_south_pole) j["flipped_after_south_pole"] = *r.flipped_after_south_pole;
  if (r.south_pole_correction) j["south_pole_correction"] = *r.south_pole_correction;
  j["mirrored"] = r.mirrored;
  j["area_distortion_conformal"] = r.area_distortion_conformal;
  if (r.moebius_iterations) {
    j["moebius_iterations"] = *r.moebius_iterations;
    j["moebius_centroid_norm"] = r.moebius_centroid_norm;
    j["area_distortion_balanced"] = r.area_distortion_balanced;
    j["moebius_kept"] = r.moebius_kept;
  }
  if (r.area_correction_steps) j["area_correction_steps"] = *r.area_correction_steps;
  if (r.density_steps) {
    Json e = Json::object();
    e["target"] = r.density_target;
    e["steps"] = *r.density_steps;
    e["log_misfit_before"] = r.density_misfit_before;
    e["log_misfit_after"] = r.density_misfit_after;
    e["area_distortion"] = r.area_distortion_density;
    e["kept"] = r.density_kept;
    if (!r.density_solver.empty()) e["solver"] = r.density_solver;
    if (r.placement.density_solve) e["placement"] = to_json(r.placement);
    j["density"] = e;
  }
  j["start"] = r.start;
  if (r.conformal_log_misfit) j["conformal_log_misfit"] = *r.conformal_log_misfit;
  if (r.progressive_log_misfit) j["progressive_log_misfit"] = *r.progressive_log_misfit;
  if (r.axial_log_misfit) j["axial_log_misfit"] = *r.axial_log_misfit;
  if (r.progressive_passes) {
    Json p = Json::object();
    p["passes"] = *r.progressive_passes;
    p["collapses"] = r.progressive_collapses;
    p["sweeps"] = r.progressive_sweeps;
    p["seconds"] = r.progressive_seconds;
    j["progressive"] = p;
  }
  if (r.start == "axial") {
    Json a = Json::object();
    a["seconds"] = r.axial_seconds;
    j["axial"] = a;
  }
  if (r.flipped_before_repair) j["flipped_before_repair"] = *r.flipped_before_repair;
  if (r.repair_steps) j["repair_steps"] = *r.repair_steps;
  j["area_distortion_final"] = r.area_distortion_final;
  j["flipped_triangles"] = r.flipped_triangles;
  Json t = Json::object();
  t["conformal"] = r.seconds_conformal;
  t["moebius"] = r.seconds_moebius;
  t["density"] = r.seconds_density;
  t["density_solve"] = r.seconds_density_solve;
  j["timings_s"] = t;
  return j;
}

}  // namespace vpm
