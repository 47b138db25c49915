// The area-preserving map of a closed genus-0 surface to the unit sphere (vpm/surface_map.hpp):
// the sphere map of the initial map's step 2, then the polish of the face areas
// (map/surface_polish.hpp); and the surface map's report.
#include "vpm/surface_map.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "linalg/sparse_cholesky.hpp"
#include "map/surface_area.hpp"
#include "map/surface_polish.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/topology.hpp"

namespace vpm {

Json to_json(const SurfaceMapReport& r) {
  Json j = Json::object();
  j["domain"] = to_string(r.domain);
  j["input"]["vertices"] = r.vertices;
  j["input"]["faces"] = r.faces;
  j["input"]["reversed"] = r.reversed;
  j["initial"] = to_json(r.initial);
  j["final"] = to_json(r.final);
  Json& rounds = j["rounds"] = Json::array();
  for (size_t k = 0; k < r.polish.size(); ++k) {
    const SurfaceMapStep& s = r.polish[k];
    Json o = Json::object();
    o["round"] = static_cast<int>(k) + 1;
    o["kind"] = "polish";
    o["face_mean_abs_dev"] = s.face_mean_abs_dev;
    o["solver_iterations"] = s.solver_iterations;
    o["solver_residual"] = s.solver_residual;
    o["step_fraction"] = s.step;
    o["frozen_vertices"] = s.frozen_vertices;
    o["discarded"] = s.discarded;
    o["seconds"] = s.seconds;
    rounds.push_back(o);
  }
  if (r.domain == SurfaceDomain::sphere) {
    j["sphere_map"] = to_json(r.sphere);
  } else {
    j["disk_map"]["boundary_vertices"] = r.boundary_vertices;
    j["disk_map"]["ears"] = r.ears;
    j["disk_map"]["split_edges"] = r.split_edges;
    j["disk_map"]["weights"] = "mean value";
  }
  j["stop_reason"] = r.stop_reason;
  j["converged"] = r.converged;
  j["convergence"]["tolerance"] = r.tolerance;
  j["convergence"]["reached"] = r.final.face_area_ratio.mean_abs_dev;
  j["convergence"]["converged"] = r.converged;
  j["timings_s"][r.domain == SurfaceDomain::sphere ? "sphere_map" : "disk_map"] = r.seconds_sphere_map;
  j["timings_s"]["polish"] = r.seconds_polish;
  j["timings_s"]["total"] = r.seconds_total;
  return j;
}

namespace {

Eigen::Vector3d row3v(const Points& x, int i) { return x.row(i).transpose(); }

// A surface with inward faces (negative enclosed volume) is mapped with its faces reversed: the
// sphere map and the flip test want outward ones.
bool faces_inward(const TriSurface& s) {
  double volume6 = 0;
  const Eigen::Vector3d c = s.vertices.colwise().mean().transpose();
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    volume6 += (row3v(s.vertices, s.triangles(t, 0)) - c)
                   .dot((row3v(s.vertices, s.triangles(t, 1)) - c).cross(row3v(s.vertices, s.triangles(t, 2)) - c));
  return volume6 < 0;
}

}  // namespace

SurfaceMapResult map_to_sphere(const TriSurface& input, const SurfaceMapOptions& opt, Device* device) {
  const auto t_total = Clock::now();
  validate_closed_surface(input, "surface");
  SurfaceMapResult res;
  SurfaceMapReport& rep = res.report;
  rep.vertices = static_cast<int>(input.vertices.rows());
  rep.faces = static_cast<int>(input.triangles.rows());
  rep.tolerance = opt.tolerance;
  TriSurface s;
  s.vertices = input.vertices;
  s.triangles = input.triangles;
  rep.reversed = faces_inward(s);
  if (rep.reversed) s.triangles.col(1).swap(s.triangles.col(2));
  const Triangles& f = s.triangles;

  auto t0 = Clock::now();
  // alone here, the sphere map's factorisations may use a few BLAS threads (linalg/sparse_cholesky.hpp)
  const detail::BlasThreadsScope blas(4);
  SphereMapResult sm = sphere_map(s, opt.sphere, device);
  rep.sphere = sm.report;
  rep.seconds_sphere_map = seconds_since(t0);
  const detail::SurfaceDomainMoves domain{SurfaceDomain::sphere, {}, {}};
  Points x = domain.place(sm.sphere);
  rep.initial = surface_metrics(s.vertices, x, f);
  if (rep.initial.flipped_faces > 0)
    throw NumericalError("map_to_sphere: the sphere map left " + std::to_string(rep.initial.flipped_faces) +
                         " flipped faces");
  const Eigen::VectorXd area0 = detail::face_areas(s.vertices, f);
  double d = rep.initial.face_area_ratio.mean_abs_dev;
  if (opt.progress) opt.progress(strprintf("sphere map: face area mean |r-1| %.4f, %.2f s", d, rep.seconds_sphere_map));

  detail::polish_surface(domain, f, area0, opt, x, rep);
  res.sphere = std::move(x);
  rep.final = surface_metrics(s.vertices, res.sphere, f);
  rep.converged = rep.final.face_area_ratio.mean_abs_dev <= opt.tolerance;
  rep.seconds_total = seconds_since(t_total);
  return res;
}

}  // namespace vpm
