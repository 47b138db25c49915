// The volume-preserving map (vpm/volume_map.hpp): options, checks, set-up and the report; the
// rounds are in map/volume_map_rounds.cpp, their steps in map/volume_map_steps.cpp.
#include "vpm/volume_map.hpp"

#include <Eigen/Core>
#include <string>

#include "map/volume_map_context.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"

namespace vpm {

const char* detail::to_string(detail::Rounds r) {
  switch (r) {
    case detail::Rounds::moser: return "moser";
    case detail::Rounds::paper: return "paper";
    case detail::Rounds::vsem: return "vsem";
  }
  return "?";
}
MapBoundary parse_map_boundary(const std::string& s) {
  if (s == "auto") return MapBoundary::automatic;
  if (s == "slide") return MapBoundary::slide;
  if (s == "fixed") return MapBoundary::fixed;
  throw InputError("volume map boundary '" + s + "' is not one of auto, slide, fixed");
}
const char* to_string(MapBoundary m) {
  switch (m) {
    case MapBoundary::automatic: return "auto";
    case MapBoundary::slide: return "slide";
    case MapBoundary::fixed: return "fixed";
  }
  return "?";
}

Json to_json(const VolumeMapRound& r) {
  Json j = Json::object();
  j["round"] = r.round;
  j["kind"] = r.kind;
  j["vertex_mean_abs_dev"] = r.vertex_mean_abs_dev;
  j["tet_mean_abs_dev"] = r.tet_mean_abs_dev;
  j["folds_before_untangle"] = r.folds_before_untangle;
  j["folds"] = r.folds;
  j["untangled"] = r.untangled;
  j["discarded"] = r.discarded;
  j["t_end"] = r.t_end;
  j["solver_iterations"] = r.solver_iterations;
  j["solver_residual"] = r.solver_residual;
  j["walk_steps_per_location"] = r.walk_steps_per_location;
  j["grid_fallbacks"] = static_cast<double>(r.grid_fallbacks);
  j["clamped"] = static_cast<double>(r.clamped);
  Json t = Json::object();
  t["solve"] = r.time_solve;
  t["field"] = r.time_field;
  t["advect"] = r.time_advect;
  t["untangle"] = r.time_untangle;
  t["total"] = r.time_total;
  j["timings_s"] = t;
  return j;
}

Json to_json(const VolumeMapResult& res) {
  Json j = Json::object();
  j["method"] = res.method;
  j["boundary"] = res.slide ? "slide" : "fixed";
  j["solver"] = res.solver;
  j["preconditioner"] = res.preconditioner;
  j["rk_steps"] = res.rk_steps;
  j["advection"] = res.device_advection ? "device" : "host";
  j["placement"] = to_json(res.placement);
  Json ji = Json::object();
  ji["vertex_mean_abs_dev"] = res.initial_vertex_mean_abs_dev;
  ji["tet_mean_abs_dev"] = res.initial_tet_mean_abs_dev;
  j["initial"] = ji;
  Json jf = Json::object();
  jf["vertex_mean_abs_dev"] = res.final_vertex_mean_abs_dev;
  jf["tet_mean_abs_dev"] = res.final_tet_mean_abs_dev;
  jf["inverted_tets"] = res.final_folds;
  j["final"] = jf;
  j["stop_reason"] = res.stop_reason;
  Json rounds = Json::array();
  for (const VolumeMapRound& r : res.rounds) rounds.push_back(to_json(r));
  j["rounds"] = rounds;
  Json jt = Json::object();
  jt["solve"] = res.timings.solve;
  jt["field"] = res.timings.field;
  jt["advect"] = res.timings.advect;
  jt["untangle"] = res.timings.untangle;
  jt["total"] = res.timings.total;
  j["timings_s"] = jt;
  return j;
}

namespace {

void check_inputs(const Points& reference, const Tets& tets, const Points& ball, const VolumeMapOptions& opt) {
  if (reference.rows() != ball.rows())
    throw InputError("volume map: reference has " + std::to_string(reference.rows()) +
                     " vertices but the ball map has " + std::to_string(ball.rows()));
  if (tets.rows() == 0) throw InputError("volume map: no tets");
  if (tets.minCoeff() < 0 || tets.maxCoeff() >= reference.rows())
    throw InputError("volume map: tet vertex index out of range");
  if (opt.rk_steps < 1) throw InputError("volume map: rk_steps must be >= 1");
  if (!(opt.polish_min_gain >= 0 && opt.polish_min_gain < 1))
    throw InputError("volume map: polish_min_gain must be in [0, 1)");
}

// Boundary, frozen vertices, neighbours, normalised input volumes, solver and advector.
void set_up(detail::MapContext& c) {
  const VolumeMapOptions& opt = c.opt;
  const Tets& tets = c.tets;
  c.n = static_cast<int>(c.ref.rows());
  c.m = static_cast<int>(tets.rows());
  const MapBoundary bm = opt.boundary != MapBoundary::automatic
                             ? opt.boundary
                             : (c.rounds == detail::Rounds::moser ? MapBoundary::slide : MapBoundary::fixed);
  c.slide = bm == MapBoundary::slide && c.rounds != detail::Rounds::vsem;  // vsem: boundary frozen
  if (c.pc.topology) {
    c.nbr = c.pc.topology->neighbours;
    c.bfaces = c.pc.topology->boundary;
    c.boundary = c.pc.topology->boundary_vertex;
  } else {
    c.nbr = detail::tet_neighbors(tets, &c.bfaces);
    c.boundary = boundary_vertex_mask(c.n, c.bfaces);
  }
  c.frozen = c.boundary;
  for (size_t v = 0; v < c.pc.pinned.size(); ++v)
    if (c.pc.pinned[v]) c.frozen[v] = 1;
  for (const VolumeAnchor& a : c.pc.anchors)
    for (int v : a.vertices) c.frozen[static_cast<size_t>(v)] = 1;
  c.vertex_tet.assign(static_cast<size_t>(c.n), 0);
  for (int t = c.m - 1; t >= 0; --t)
    for (int k = 0; k < 4; ++k) c.vertex_tet[tets(t, k)] = t;
  const Eigen::VectorXd v0 = tet_volumes(c.ref, tets);
  const double s0 = v0.sum();
  if (!(s0 > 0)) throw InputError("volume map: the reference mesh has no positive volume");
  c.ref_tet = v0 / s0;
  c.ref_dual = Eigen::VectorXd::Zero(c.n);
  for (int t = 0; t < c.m; ++t)
    for (int k = 0; k < 4; ++k) c.ref_dual(tets(t, k)) += 0.25 * c.ref_tet(t);
  c.solver = std::make_unique<detail::MapSolver>(c.dev, c.n, tets, opt.solver, opt.solver_tolerance,
                                                   opt.preconditioner, opt.poisson);
  // where the parts run (VolumeMapOptions::advection, ::polish; the rules: vpm/placement.hpp)
  // (a polish on its own never advects: no advector, no advection placed)
  if (!c.pc.only && c.rounds == detail::Rounds::moser) {
    if (c.placement.decide(c.dev, PlacedWork::advection, opt.advection)) {
      c.advector = std::make_unique<detail::DeviceAdvector>(c.dev, tets, c.nbr, c.boundary);
      c.gradients_on_device = c.placement.decide(c.dev, PlacedWork::gradients, opt.advection);
    } else {
      c.advector = std::make_unique<detail::HostAdvector>(c.boundary);
    }
  }
  c.polish_on_device = c.placement.decide(c.dev, PlacedWork::polish, opt.polish);
  c.volumes = std::make_unique<detail::MeshVolumes>(c.dev, tets);
}

}  // namespace

VolumeMapResult volume_preserving_map(Device& dev, const Points& reference, const Tets& tets,
                                      Points& ball, const VolumeMapOptions& opt) {
  static const detail::PolishConstraints none;
  return detail::map_volumes(dev, reference, tets, ball, opt, none);
}

VolumeMapResult detail::map_volumes(Device& dev, const Points& reference, const Tets& tets, Points& ball,
                                    const VolumeMapOptions& opt, const PolishConstraints& pc, Rounds rounds,
                                    int paper_steps) {
  const auto t_start = Clock::now();
  check_inputs(reference, tets, ball, opt);
  detail::MapContext c(dev, reference, tets, opt, pc);
  c.rounds = rounds;
  c.paper_steps = paper_steps;
  set_up(c);
  VolumeMapResult res;
  res.method = to_string(rounds);
  res.slide = c.slide;
  res.solver = to_string(opt.solver);
  res.preconditioner = to_string(c.solver->preconditioner());
  res.rk_steps = opt.rk_steps;
  res.device_advection = c.advector && c.advector->on_device();
  res.placement = c.placement;

  // The start must be fold-free.
  if (detail::count_folds(c, ball) > 0) {
    const int left = detail::untangle_folds(c, ball, &res.timings.untangle);
    if (left > 0)
      throw NumericalError("volume map: the initial map has " + std::to_string(left) +
                           " inverted tets that local untangling could not repair");
  }
  detail::project_boundary(c, ball);
  DistortionPair d = volume_distortion(reference, ball, tets);
  res.initial_vertex_mean_abs_dev = d.vertex;
  res.initial_tet_mean_abs_dev = d.tet;

  detail::run_rounds(c, ball, res, d);
  detail::run_polish(c, ball, res, d);

  res.final_vertex_mean_abs_dev = d.vertex;
  res.final_tet_mean_abs_dev = d.tet;
  res.final_folds = detail::count_folds(c, ball);
  if (res.final_folds > 0)  // cannot happen: every accepted round is fold-free
    throw NumericalError("volume map: " + std::to_string(res.final_folds) + " inverted tets remain");
  res.timings.total = seconds_since(t_start);
  return res;
}

}  // namespace vpm
