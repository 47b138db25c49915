// to_json(InitialMapReport) (vpm/initial_map.hpp): the initial map's report object.
#include <Eigen/Dense>

#include "vpm/initial_map.hpp"
#include "vpm/json.hpp"
#include "map/initial_untangle.hpp"

namespace vpm {

namespace {

Json vec_json(const Eigen::Vector3d& v) {
  Json a = Json::array();
  for (int c = 0; c < 3; ++c) a.push_back(v(c));
  return a;
}

Json untangle_json(const InitialUntangle& u) {
  Json j = to_json(u.result);
  j["scope"] = u.local ? "local" : "global";
  if (u.local) j["rings"] = u.rings;
  return j;
}

}  // namespace

Json to_json(const InitialMapReport& r) {
  Json rep = Json::object();
  rep["device"] = r.device;
  rep["input"]["vertices"] = r.input_vertices;
  rep["input"]["tets"] = r.input_tets;
  Json& q = rep["input_quality"];
  q["min_dihedral_deg"] = r.min_dihedral_deg;
  q["min_dihedral_tet"] = r.min_dihedral_tet;
  q["tets_below_1deg"] = r.tets_below_1deg;
  q["tets_below_5deg"] = r.tets_below_5deg;
  Json list = Json::array();
  for (const WorstTet& w : r.worst) {
    Json o = Json::object();
    o["tet"] = w.tet;
    o["min_dihedral_deg"] = w.min_dihedral_deg;
    o["centroid"] = vec_json(w.centroid);
    list.push_back(o);
  }
  q["worst"] = list;
  if (r.min_dihedral_deg < 1.0)
    q["warning"] = "slivers below 1 degree: meshes with 0.01-0.05 degree slivers defeat the ball map "
                   "(docs/design.md 4.2); remesh with a dihedral bound";
  Json& s = rep["split"];
  s["rounds"] = r.split_rounds;
  s["inserted_vertices"] = r.inserted_vertices;
  s["four_boundary_tets_before"] = r.four_boundary_tets_before;
  s["four_boundary_tets_after"] = r.four_boundary_tets_after;
  s["centroid_splits"] = r.centroid_splits;
  rep["refined"]["vertices"] = r.refined_vertices;
  rep["refined"]["tets"] = r.refined_tets;
  rep["boundary"] = to_json(r.boundary);
  if (r.fallback) {
    Json& f = rep["fallback"];
    f["from"] = r.fallback->from;
    f["to"] = r.fallback->axial ? "axial" : "conformal";
    f["flipped_triangles"] = r.fallback->flipped_triangles;
    f["folds_after_untangle"] = r.fallback->folds_after_untangle;
    f["seconds"] = r.fallback->seconds;
    f["crowded"] = r.fallback->crowded;
    f["crowded_by_boundary"] = r.fallback->crowded_by_boundary;
    f["conformal_min_tet_ratio"] = r.fallback->conformal_min_tet_ratio;
    f["axial"] = r.fallback->axial;
  }
  rep["harmonic"]["solver"] = r.harmonic_on_device ? "PoissonSolver CG (OpenCL)" : "PoissonSolver CG (host)";
  rep["harmonic"]["preconditioner"] = r.harmonic_preconditioner;
  rep["harmonic"]["iterations"] = r.harmonic_iterations;
  rep["harmonic"]["relative_residual"] = r.harmonic_relative_residual;
  rep["harmonic"]["inverted_tets"] = r.folds_before_untangle;
  rep["folds_before_untangle"] = r.folds_before_untangle;
  if (r.untangle) rep["untangle"] = untangle_json(*r.untangle);
  if (r.untangle_local_failed) rep["untangle_local_failed"] = untangle_json(*r.untangle_local_failed);
  if (r.untangle_cleanup) rep["untangle_cleanup"] = untangle_json(*r.untangle_cleanup);
  if (r.untangle_slide) rep["untangle_slide"] = untangle_json(*r.untangle_slide);
  rep["folds_after_untangle"] = r.folds_after_untangle;
  if (r.refine) {
    Json& f = rep["refine"];
    f["rounds"] = r.refine->rounds;
    f["inserted_vertices"] = r.refine->inserted_vertices;
    f["folds_before"] = r.refine->folds_before;
    f["folds_after"] = r.refine->folds_after;
    f["seconds"] = r.refine->seconds;
  }
  rep["boundary_max_radius_error"] = r.boundary_max_radius_error;
  rep["metrics"] = to_json(r.metrics);
  Json& tm = rep["timings_s"];
  tm["input_quality"] = r.timings.input_quality;
  tm["metrics"] = r.timings.metrics;
  tm["split"] = r.timings.split;
  tm["boundary"] = r.timings.boundary;
  tm["harmonic"] = r.timings.harmonic;
  tm["untangle"] = r.timings.untangle;
  tm["total"] = r.timings.total;
  return rep;
}

}  // namespace vpm
