#include "vpm/volume_map.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>

#include "map/moser_field.hpp"
#include "map/polish.hpp"
#include "map/volume_map_solve.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

#if __has_include("vpm/untangle.hpp")
#include "vpm/untangle.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"
#define VPM_VOLUME_MAP_HAVE_UNTANGLE 1
#else
#define VPM_VOLUME_MAP_HAVE_UNTANGLE 0
#endif

namespace vpm {

VolumeMapMethod parse_volume_map_method(const std::string& s) {
  if (s == "moser") return VolumeMapMethod::moser;
  if (s == "paper") return VolumeMapMethod::paper;
  if (s == "vsem") return VolumeMapMethod::vsem;
  throw InputError("--method: '" + s + "' is not one of moser, paper, vsem");
}
const char* to_string(VolumeMapMethod m) {
  switch (m) {
    case VolumeMapMethod::moser: return "moser";
    case VolumeMapMethod::paper: return "paper";
    case VolumeMapMethod::vsem: return "vsem";
  }
  return "?";
}
MapBoundary parse_map_boundary(const std::string& s) {
  if (s == "auto") return MapBoundary::automatic;
  if (s == "slide") return MapBoundary::slide;
  if (s == "fixed") return MapBoundary::fixed;
  throw InputError("--boundary: '" + s + "' is not one of slide, fixed");
}
const char* to_string(MapBoundary m) {
  switch (m) {
    case MapBoundary::automatic: return "auto";
    case MapBoundary::slide: return "slide";
    case MapBoundary::fixed: return "fixed";
  }
  return "?";
}

Json VolumeMapRound::to_json() const {
  Json j = Json::object();
  j["round"] = round;
  j["kind"] = kind;
  j["vertex_mean_abs_dev"] = vertex_mean_abs_dev;
  j["tet_mean_abs_dev"] = tet_mean_abs_dev;
  j["folds_before_untangle"] = folds_before_untangle;
  j["folds"] = folds;
  j["untangled"] = untangled;
  j["discarded"] = discarded;
  j["t_end"] = t_end;
  j["solver_iterations"] = solver_iterations;
  j["solver_residual"] = solver_residual;
  j["walk_steps_per_location"] = walk_steps_per_location;
  j["grid_fallbacks"] = static_cast<double>(grid_fallbacks);
  j["clamped"] = static_cast<double>(clamped);
  Json t = Json::object();
  t["solve"] = time_solve;
  t["field"] = time_field;
  t["advect"] = time_advect;
  t["untangle"] = time_untangle;
  t["total"] = time_total;
  j["timings_s"] = t;
  return j;
}

DistortionPair volume_distortion(const Points& ref, const Points& x, const Tets& tets) {
  const Eigen::VectorXd v0 = tet_volumes(ref, tets), v1 = tet_volumes(x, tets);
  const double s0 = v0.sum(), s1 = v1.sum();
  DistortionPair d;
  Eigen::VectorXd d0 = Eigen::VectorXd::Zero(ref.rows()), d1 = Eigen::VectorXd::Zero(ref.rows());
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    d.tet += std::fabs((v1(t) / s1) / (v0(t) / s0) - 1.0);
    d.folds += v1(t) <= 0;
    for (int c = 0; c < 4; ++c) {
      d0(tets(t, c)) += v0(t);
      d1(tets(t, c)) += v1(t);
    }
  }
  int used = 0;
  for (Eigen::Index i = 0; i < ref.rows(); ++i)
    if (d0(i) != 0) {
      d.vertex += std::fabs((d1(i) / s1) / (d0(i) / s0) - 1.0);
      ++used;
    }
  d.tet /= std::max<Eigen::Index>(1, tets.rows());
  d.vertex /= std::max(1, used);
  return d;
}

namespace {



struct Ctx {
  Device& dev;
  const Points& ref;
  const Tets& tets;
  const VolumeMapOptions& opt;
  int n = 0, m = 0;
  bool slide = true;
  std::vector<char> boundary;
  std::vector<char> frozen;       // never moved by untangling: boundary or pinned
  std::vector<int> nbr;
  std::vector<int> vertex_tet;    // one tet incident to each vertex
  Eigen::VectorXd ref_dual;       // input dual volumes / input total volume
  Eigen::VectorXd ref_tet;        // input tet volumes / input total volume
  std::unique_ptr<detail::MapSolver> solver;
  std::unique_ptr<detail::DeviceAdvector> advector;
  Eigen::VectorXd psi;
  Triangles bfaces;  // boundary faces (outward), built on first use
  std::vector<char> freedom;                          // polish: free / tangent / fixed per vertex
  std::unique_ptr<detail::DevicePolisher> polisher;   // polish on the device, built on first use

  Ctx(Device& d, const Points& r, const Tets& t, const VolumeMapOptions& o) : dev(d), ref(r), tets(t), opt(o) {}
  bool pinned(int v) const { return !opt.pinned.empty() && opt.pinned[static_cast<size_t>(v)]; }
};

int count_folds(Ctx& c, const Points& x) {
  const Eigen::VectorXd v = tet_volumes(c.dev, x, c.tets);
  return static_cast<int>((v.array() <= 0).count());
}

std::vector<int> folded_list(const Points& x, const Tets& tets) {
  const Eigen::VectorXd v = tet_volumes(x, tets);
  std::vector<int> out;
  for (Eigen::Index t = 0; t < v.size(); ++t)
    if (v(t) <= 0) out.push_back(static_cast<int>(t));
  return out;
}

// Local untangling of the folded tets of x (boundary fixed; when sliding and `before` is given,
// boundary triangles flipped on the sphere are unflipped first). Returns the folds left.
int untangle_folds(Ctx& c, Points& x, double* seconds, const Points* before = nullptr) {
  const auto t0 = Clock::now();
  std::vector<int> folded = folded_list(x, c.tets);
  if (folded.empty()) return 0;
#if VPM_VOLUME_MAP_HAVE_UNTANGLE
  if (c.opt.local_untangle && c.slide && before) {
    if (c.bfaces.rows() == 0) c.bfaces = boundary_faces(c.tets);
    unflip_sphere_faces(*before, c.bfaces, x, c.opt.pinned);
    folded = folded_list(x, c.tets);
  }
  if (c.opt.local_untangle) {
    for (int rings = 2; rings <= 4 && !folded.empty(); rings += 2) {
      untangle_local(c.ref, c.tets, x, c.frozen, folded, rings, untangle_local_options());
      folded = folded_list(x, c.tets);
    }
  }
#endif
  if (seconds) *seconds += seconds_since(t0);
  return static_cast<int>(folded.size());
}

// Vertex gradients (eq. 13): volume-weighted averages of the per-tet gradients; normal part
// removed at boundary vertices (or zero there when the boundary is fixed).
std::vector<double> vertex_gradients(const Ctx& c, const Points& x,
                                     const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& G,
                                     const Eigen::VectorXd& vol) {
  std::vector<double> g(3 * static_cast<size_t>(c.n), 0.0), w(static_cast<size_t>(c.n), 0.0);
  for (int t = 0; t < c.m; ++t)
    for (int k = 0; k < 4; ++k) {
      const int v = c.tets(t, k);
      w[v] += vol(t);
      for (int d = 0; d < 3; ++d) g[3 * v + d] += vol(t) * G(t, d);
    }
  for (int v = 0; v < c.n; ++v) {
    Eigen::Map<Eigen::Vector3d> gv(&g[3 * static_cast<size_t>(v)]);
    if (w[v] > 0) gv /= w[v];
    if (c.boundary[v]) {
      if (!c.slide) {
        gv.setZero();
      } else {
        const Eigen::Vector3d nrm = x.row(v).transpose().normalized();
        gv -= gv.dot(nrm) * nrm;
      }
    }
  }
  return g;
}

// Dual volumes, targets rescaled to the current total, rho0 = m / V, and the Neumann solve
// K psi = m - V. Returns V and m.
void solve_round(Ctx& c, const Points& x, Eigen::VectorXd& V, Eigen::VectorXd& target,
                 VolumeMapRound& r) {
  const auto t0 = Clock::now();
  V = dual_volumes(c.dev, x, c.tets);
  target = c.ref_dual * V.sum();
  const Eigen::VectorXd b = target - V;
  c.psi.setZero(c.n);
  const detail::SolveStats s = c.solver->neumann(x, b, c.psi);
  r.solver_iterations += s.iterations;
  r.solver_residual = std::max(r.solver_residual, s.residual);
  r.time_solve += seconds_since(t0);
}

// One Moser round on [0, t_end]: x in/out.
void moser_round(Ctx& c, Points& x, double t_end, VolumeMapRound& r) {
  Eigen::VectorXd V, target;
  solve_round(c, x, V, target, r);
  const auto t1 = Clock::now();
  detail::MoserField f;
  detail::build_background(f, x, c.tets, c.nbr);
  const auto G = detail::tet_gradients(f, c.psi);
  const Eigen::VectorXd vol = tet_volumes(x, c.tets);
  f.grad = vertex_gradients(c, x, G, vol);
  f.rho0.resize(static_cast<size_t>(c.n));
  for (int i = 0; i < c.n; ++i) f.rho0[i] = V(i) > 0 ? target(i) / V(i) : 1.0;
  r.time_field += seconds_since(t1);

  const auto t2 = Clock::now();
  detail::AdvectParams p;
  p.steps = std::max(1, c.opt.rk_steps);
  p.t_end = t_end;
  p.slide = c.slide;
  std::vector<int> hint = c.vertex_tet;
  detail::AdvectStats st;
  if (c.advector) {
    c.advector->set_field(f);
    c.advector->advect(p, x, hint, &st);
  } else {
    detail::advect_host(f, c.boundary, p, x, hint, &st);
  }
  r.time_advect += seconds_since(t2);
  r.walk_steps_per_location = st.locations ? double(st.walk_steps) / double(st.locations) : 0.0;
  r.grid_fallbacks += st.grid_fallbacks;
  r.clamped += st.clamped;
}

// The paper's explicit step: re-solve on the current geometry, x += dt grad psi / rho.
void paper_step(Ctx& c, Points& x, double dt, VolumeMapRound& r) {
  Eigen::VectorXd V, target;
  solve_round(c, x, V, target, r);
  const auto t1 = Clock::now();
  detail::MoserField f;
  detail::build_background(f, x, c.tets, c.nbr);
  const auto G = detail::tet_gradients(f, c.psi);
  const Eigen::VectorXd vol = tet_volumes(x, c.tets);
  const std::vector<double> g = vertex_gradients(c, x, G, vol);
  r.time_field += seconds_since(t1);
  const auto t2 = Clock::now();
  for (int i = 0; i < c.n; ++i) {
    if (c.boundary[i] && !c.slide) continue;
    const double rho = V(i) > 0 ? target(i) / V(i) : 1.0;
    Eigen::Vector3d p = x.row(i).transpose() + dt / rho * Eigen::Vector3d(g[3 * i], g[3 * i + 1], g[3 * i + 2]);
    if (c.boundary[i]) p.normalize();
    x.row(i) = p.transpose();
  }
  r.time_advect += seconds_since(t2);
}

// Polish: one Gauss-Newton direction on the relative tet volumes (host/polish.hpp): on a GPU
// with the OpenCL kernels, otherwise on the host threads (on PoCL the kernels were 2x slower
// than the threaded host loops at 1.1M tets: 3.1-4.7 s against 1.7-2.2 s per step).
void polish_step(Ctx& c, Points& x, VolumeMapRound& r, Points& dx_out) {
  const auto t0 = Clock::now();
  const Eigen::VectorXd vol = tet_volumes(x, c.tets);
  const Eigen::VectorXd target = c.ref_tet * vol.sum();
  if (c.freedom.empty()) c.freedom = detail::polish_freedom(c.boundary, c.slide, c.opt.pinned);
  detail::PolishDirection d;
  if (!c.dev.is_host() && !c.opt.force_host_advection && c.dev.description().type == "gpu") {
    if (!c.polisher) c.polisher = std::make_unique<detail::DevicePolisher>(c.dev, c.tets, c.n, c.freedom);
    d = c.polisher->direction(x, target, c.opt.polish_iterations);
  } else {
    d = detail::polish_direction_host(x, c.tets, target, c.freedom, c.opt.polish_iterations);
  }
  r.solver_iterations += d.iterations;
  r.solver_residual = d.residual;
  r.time_solve += seconds_since(t0);
  dx_out = std::move(d.dx);
}

}  // namespace

VolumeMapResult volume_preserving_map(Device& dev, const Points& reference, const Tets& tets,
                                      Points& ball, const VolumeMapOptions& opt) {
  const auto t_start = Clock::now();
  if (reference.rows() != ball.rows())
    throw InputError("volume map: reference has " + std::to_string(reference.rows()) +
                     " vertices but the ball map has " + std::to_string(ball.rows()));
  if (tets.rows() == 0) throw InputError("volume map: no tets");
  if (tets.minCoeff() < 0 || tets.maxCoeff() >= reference.rows())
    throw InputError("volume map: tet vertex index out of range");
  if (opt.rk_steps < 1) throw InputError("volume map: rk_steps must be >= 1");

  Ctx c(dev, reference, tets, opt);
  c.n = static_cast<int>(reference.rows());
  c.m = static_cast<int>(tets.rows());
  const MapBoundary bm = opt.boundary != MapBoundary::automatic
                              ? opt.boundary
                              : (opt.method == VolumeMapMethod::moser ? MapBoundary::slide : MapBoundary::fixed);
  c.slide = bm == MapBoundary::slide;
  if (opt.method == VolumeMapMethod::vsem) c.slide = false;  // vsem: boundary frozen
  c.boundary = boundary_vertex_mask(c.n, boundary_faces(tets));
  if (!opt.pinned.empty() && static_cast<int>(opt.pinned.size()) != c.n)
    throw InputError("volume map: pinned has " + std::to_string(opt.pinned.size()) + " entries for " +
                     std::to_string(c.n) + " vertices");
  if (!opt.pinned.empty() && !opt.polish_only)
    throw InputError("volume map: pinned vertices need polish_only (Moser rounds move every vertex)");
  if (opt.polish_only && opt.method != VolumeMapMethod::moser)
    throw InputError("volume map: polish_only needs the moser method");
  c.frozen = c.boundary;
  for (size_t v = 0; v < opt.pinned.size(); ++v)
    if (opt.pinned[v]) c.frozen[v] = 1;
  c.nbr = detail::tet_neighbors(tets);
  c.vertex_tet.assign(static_cast<size_t>(c.n), 0);
  for (int t = c.m - 1; t >= 0; --t)
    for (int k = 0; k < 4; ++k) c.vertex_tet[tets(t, k)] = t;
  {
    const Eigen::VectorXd v0 = tet_volumes(reference, tets);
    const double s0 = v0.sum();
    if (!(s0 > 0)) throw InputError("volume map: the reference mesh has no positive volume");
    c.ref_tet = v0 / s0;
    c.ref_dual = Eigen::VectorXd::Zero(c.n);
    for (int t = 0; t < c.m; ++t)
      for (int k = 0; k < 4; ++k) c.ref_dual(tets(t, k)) += 0.25 * c.ref_tet(t);
  }
  c.solver = std::make_unique<detail::MapSolver>(dev, c.n, tets, opt.solver, opt.solver_tolerance);
  if (!dev.is_host() && !opt.force_host_advection && opt.method == VolumeMapMethod::moser)
    c.advector = std::make_unique<detail::DeviceAdvector>(dev, tets, c.nbr, c.boundary);

  VolumeMapResult res;
  Json rounds_json = Json::array();
  double tt_solve = 0, tt_field = 0, tt_adv = 0, tt_unt = 0;

  // The start must be fold-free.
  if (count_folds(c, ball) > 0) {
    const int left = untangle_folds(c, ball, &tt_unt);
    if (left > 0)
      throw NumericalError("volume map: the initial map has " + std::to_string(left) +
                           " inverted tets that local untangling could not repair");
  }
  if (c.slide)
    for (int i = 0; i < c.n; ++i)
      if (c.boundary[i] && !c.pinned(i)) ball.row(i).normalize();

  DistortionPair d = volume_distortion(reference, ball, tets);
  res.initial_vertex_mean_abs_dev = d.vertex;
  res.initial_tet_mean_abs_dev = d.tet;

  int max_rounds = opt.polish_only ? 0
                   : opt.rounds >= 0 ? opt.rounds
                   : opt.max_rounds > 0 ? opt.max_rounds
                   : opt.method == VolumeMapMethod::moser ? 8
                   : opt.method == VolumeMapMethod::paper ? opt.paper_steps
                                                          : 15;
  res.stop_reason = opt.polish_only ? "polish_only" : "rounds";
  double paper_dt = 1.0 / std::max(1, opt.paper_steps);
  Eigen::VectorXd vsem_w = Eigen::VectorXd::Ones(c.m);
  double prev_vertex = d.vertex;

  for (int k = 1; k <= max_rounds; ++k) {
    if (opt.rounds < 0 && d.vertex <= opt.tolerance) {
      res.stop_reason = "tolerance";
      break;
    }
    const auto t_round = Clock::now();
    VolumeMapRound r;
    r.round = k;
    r.kind = to_string(opt.method);
    const Points saved = ball;
    double t_end = opt.method == VolumeMapMethod::paper ? paper_dt : 1.0;
    int folds = 0;
    Points vsem_target;
    if (opt.method == VolumeMapMethod::vsem) {
      // weights *= current normalised tet volume ratio; harmonic map with the boundary frozen
      const Eigen::VectorXd v1 = tet_volumes(ball, tets);
      const Eigen::VectorXd ratio = (v1 / v1.sum()).array() / c.ref_tet.array();
      vsem_w.array() *= ratio.array().max(1e-6);
      vsem_w /= vsem_w.mean();
      const auto t0 = Clock::now();
      const auto K = detail::weighted_stiffness(reference, tets, &vsem_w);
      vsem_target = ball;
      const detail::SolveStats s = c.solver->dirichlet(K, c.boundary, vsem_target);
      r.solver_iterations = s.iterations;
      r.solver_residual = s.residual;
      r.time_solve += seconds_since(t0);
    }
    for (int attempt = 0; attempt <= opt.max_step_halvings; ++attempt) {
      if (attempt > 0) ball = saved;
      if (opt.method == VolumeMapMethod::moser) {
        moser_round(c, ball, t_end, r);
      } else if (opt.method == VolumeMapMethod::paper) {
        paper_step(c, ball, t_end, r);
      } else {
        ball = saved + t_end * (vsem_target - saved);
      }
      folds = count_folds(c, ball);
      r.folds_before_untangle = folds;
      if (folds > 0) {
        r.untangled = VPM_VOLUME_MAP_HAVE_UNTANGLE && opt.local_untangle;
        folds = untangle_folds(c, ball, &r.time_untangle, &saved);
      }
      r.t_end = t_end;
      if (folds == 0) break;
      t_end *= 0.5;
    }
    r.folds = folds;
    if (folds > 0) {
      ball = saved;
      r.discarded = true;
      r.folds = 0;
    }
    if (opt.method == VolumeMapMethod::paper && !r.discarded) paper_dt = t_end;
    d = volume_distortion(reference, ball, tets);
    r.vertex_mean_abs_dev = d.vertex;
    r.tet_mean_abs_dev = d.tet;
    r.time_total = seconds_since(t_round);
    tt_solve += r.time_solve;
    tt_field += r.time_field;
    tt_adv += r.time_advect;
    tt_unt += r.time_untangle;
    res.rounds.push_back(r);
    rounds_json.push_back(r.to_json());
    if (opt.progress) {
      std::string line = std::string(to_string(opt.method)) + " round " + std::to_string(k) + "/" +
                         std::to_string(max_rounds) +
                         strprintf(": vertex mean |r-1| %.4f, tet %.4f, %.2f s", d.vertex, d.tet, r.time_total);
      if (r.folds_before_untangle) line += ", folds " + std::to_string(r.folds_before_untangle) +
                                           (r.discarded ? " (round discarded)" : " (untangled)");
      opt.progress(line);
    }
    if (r.discarded) {
      res.stop_reason = "fold";
      break;
    }
    // Automatic stop: hand over to the polish rounds once a round gains less than half and the
    // distortion is within 5x the tolerance (polish steps remove the last few percent; far from
    // the goal, as on a C-shaped caudate at 9 %, more rounds still pay), or when a round gains
    // less than a fifth.
    if (opt.rounds < 0 && opt.method == VolumeMapMethod::moser && opt.polish_rounds > 0 &&
        d.vertex > opt.tolerance &&
        ((d.vertex > 0.5 * prev_vertex && d.vertex <= 5 * opt.tolerance) || d.vertex > 0.8 * prev_vertex)) {
      res.stop_reason = "stalled";
      break;
    }
    prev_vertex = d.vertex;
  }
  if (res.stop_reason == "rounds" && opt.rounds < 0 && d.vertex <= opt.tolerance) res.stop_reason = "tolerance";

  // Polish rounds (moser): tet-level Gauss-Newton steps, fold-checked like the rounds.
  const int n_polish = opt.method == VolumeMapMethod::moser && opt.rounds != 0 ? opt.polish_rounds : 0;
  for (int k = 1; k <= n_polish; ++k) {
    const auto t_round = Clock::now();
    VolumeMapRound r;
    r.round = static_cast<int>(res.rounds.size()) + 1;
    r.kind = "polish";
    const Points saved = ball;
    Points dx;
    polish_step(c, ball, r, dx);
    const auto t2 = Clock::now();
    double step = 1.0;
    int folds = 0;
    for (int attempt = 0; attempt <= opt.max_step_halvings + 2; ++attempt) {
      ball = saved + step * dx;
      if (c.slide)
        for (int i = 0; i < c.n; ++i)
          if (c.boundary[i] && !c.pinned(i)) ball.row(i).normalize();
      folds = count_folds(c, ball);
      if (attempt == 0) r.folds_before_untangle = folds;
      if (folds > 0) {
        r.untangled = VPM_VOLUME_MAP_HAVE_UNTANGLE && opt.local_untangle;
        folds = untangle_folds(c, ball, &r.time_untangle, &saved);
      }
      r.t_end = step;
      if (folds == 0) break;
      step *= 0.5;
    }
    r.time_advect += seconds_since(t2) - r.time_untangle;
    tt_unt += r.time_untangle;
    const DistortionPair dp = volume_distortion(reference, ball, tets);
    const bool stalled = dp.tet > 0.99 * d.tet;
    if (folds > 0 || dp.tet >= d.tet) {  // no progress or folded: undo and stop polishing
      ball = saved;
      r.discarded = true;
    } else {
      d = dp;
    }
    r.folds = 0;
    r.vertex_mean_abs_dev = d.vertex;
    r.tet_mean_abs_dev = d.tet;
    r.time_total = seconds_since(t_round);
    tt_solve += r.time_solve;
    tt_adv += r.time_advect;
    res.rounds.push_back(r);
    rounds_json.push_back(r.to_json());
    if (opt.progress)
      opt.progress("polish " + std::to_string(k) + "/" + std::to_string(n_polish) +
                   strprintf(": vertex mean |r-1| %.4f, tet %.4f, %.2f s", d.vertex, d.tet, r.time_total) +
                   (r.discarded ? " (discarded)" : ""));
    if (r.discarded || stalled) break;
  }

  res.final_vertex_mean_abs_dev = d.vertex;
  res.final_tet_mean_abs_dev = d.tet;
  res.final_folds = count_folds(c, ball);
  if (res.final_folds > 0)  // cannot happen: every accepted round is fold-free
    throw NumericalError("volume map: " + std::to_string(res.final_folds) + " inverted tets remain");

  Json j = Json::object();
  j["method"] = to_string(opt.method);
  j["boundary"] = c.slide ? "slide" : "fixed";
  j["solver"] = opt.solver;
  j["rk_steps"] = opt.rk_steps;
  j["advection"] = c.advector ? "device" : "host";
  j["local_untangle_available"] = static_cast<bool>(VPM_VOLUME_MAP_HAVE_UNTANGLE);
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
  j["rounds"] = rounds_json;
  Json jt = Json::object();
  jt["solve"] = tt_solve;
  jt["field"] = tt_field;
  jt["advect"] = tt_adv;
  jt["untangle"] = tt_unt;
  jt["total"] = seconds_since(t_start);
  j["timings_s"] = jt;
  res.report = j;
  return res;
}

}  // namespace vpm
