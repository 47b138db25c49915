// Initial map of a tet mesh to the unit ball (see vpm/initial_map.hpp).
#include "vpm/initial_map.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <future>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <utility>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/metrics.hpp"
#include "vpm/solver.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"
#include "map/initial_untangle.hpp"

namespace vpm {

namespace {

Eigen::Vector3d tet_centroid(const Points& x, const Tets& t, int i) {
  return 0.25 * (x.row(t(i, 0)) + x.row(t(i, 1)) + x.row(t(i, 2)) + x.row(t(i, 3))).transpose();
}

void check_input(const TetMesh& input) {
  if (input.num_tets() == 0) throw InputError("initial_map: the mesh has no tets");
  const Eigen::VectorXd v = tet_volumes(input.vertices, input.tets);
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!(v(i) > 0))
      throw InputError("initial_map: input tet " + std::to_string(i) + " is not positively oriented (volume " +
                       format_sig(v(i)) + "); validate the mesh first");
}

// Input quality: smallest dihedral angles, counts below 1 and 5 degrees, the worst tets.
void measure_quality(const TetMesh& input, int worst_count, InitialMapReport& rep) {
  const Eigen::VectorXd tmin = min_dihedral_angles_deg(input.vertices, input.tets);
  Eigen::Index worst = 0;
  rep.min_dihedral_deg = tmin.minCoeff(&worst);
  rep.min_dihedral_tet = static_cast<int>(worst);
  rep.tets_below_1deg = static_cast<int>((tmin.array() < 1.0).count());
  rep.tets_below_5deg = static_cast<int>((tmin.array() < 5.0).count());
  std::vector<int> order(tmin.size());
  std::iota(order.begin(), order.end(), 0);
  const int nw = std::min<int>(worst_count, static_cast<int>(order.size()));
  std::partial_sort(order.begin(), order.begin() + nw, order.end(), [&](int a, int b) { return tmin(a) < tmin(b); });
  for (int i = 0; i < nw; ++i)
    rep.worst.push_back({order[i], tmin(order[i]), tet_centroid(input.vertices, input.tets, order[i])});
}

// "input smallest dihedral angle ... at tet ... (x, y, z)": appended to numerical failures.
std::string quality_note(const TetMesh& input, const InitialMapReport& rep) {
  const Eigen::Vector3d c = tet_centroid(input.vertices, input.tets, rep.min_dihedral_tet);
  return "input smallest dihedral angle " + format_sig(rep.min_dihedral_deg) + " deg at tet " +
         std::to_string(rep.min_dihedral_tet) + " (" + format_sig(c(0)) + ", " + format_sig(c(1)) + ", " +
         format_sig(c(2)) + ")";
}

// Step 1, or the input as it is (InitialMapOptions::split_edges false).
SplitResult split(const TetMesh& input, const Triangles& boundary, const InitialMapOptions& opt,
                  InitialMapReport& rep) {
  SplitResult sp;
  if (opt.split_edges) {
    sp = split_boundary_edges(input, boundary, opt.max_split_rounds);
  } else {
    sp.mesh = input;
    sp.mesh.set_point_field("original_position", FieldValues(input.vertices));
    sp.parent_tet.resize(input.num_tets());
    std::iota(sp.parent_tet.begin(), sp.parent_tet.end(), 0);
    sp.boundary = boundary;
  }
  rep.split_rounds = sp.rounds;
  rep.inserted_vertices = sp.inserted_vertices;
  rep.four_boundary_tets_before = sp.four_boundary_tets_before;
  rep.four_boundary_tets_after = sp.four_boundary_tets_after;
  rep.centroid_splits = sp.centroid_splits;
  rep.refined_vertices = sp.mesh.num_vertices();
  rep.refined_tets = sp.mesh.num_tets();
  return sp;
}

SolverOptions harmonic_solver_options(const InitialMapOptions& opt, const Device& device, long long tets) {
  SolverOptions so;
  so.relative_tolerance = opt.solver_tolerance;
  so.preconditioner = choose_preconditioner(opt.preconditioner, device, tets);
  return so;
}

// The harmonic step's Poisson solver on m (Laplacian pattern, device buffers, K at the input
// positions), started on a second thread: it needs only the tets, and the sphere map that runs
// meanwhile is host code on one thread (0.4 s of the 1.1M-tet map hidden).
std::future<std::shared_ptr<PoissonSolver>> start_harmonic_solver(Device& device, const TetMesh& m,
                                                                   const InitialMapOptions& opt) {
  return std::async(std::launch::async, [&device, &m, so = harmonic_solver_options(opt, device, m.num_tets())] {
    auto ps = std::make_shared<PoissonSolver>(device, m.num_vertices(), m.tets, so);
    ps->set_positions(m.vertices);
    return ps;
  });
}

// Step 3: the harmonic interior with the boundary on `sphere`, on the shared Poisson solver
// `ps` (Jacobi CG on the host or the OpenCL device; kept for the volume map). Returns the ball
// positions.
Points harmonic_interior(const TetMesh& m, const std::vector<char>& boundary, const Points& sphere,
                         const InitialMapOptions& opt, const std::string& note, InitialMapReport& rep,
                         PoissonSolver& ps) {
  const int n = m.num_vertices();
  // warm start: interior vertices at their input position mapped to the ball's scale
  FieldValues u = FieldValues::Zero(n, 3);
  const Eigen::RowVector3d c = m.vertices.colwise().mean();
  const double r = (m.vertices.rowwise() - c).rowwise().norm().maxCoeff();
  for (int i = 0; i < n; ++i)
    u.row(i) = boundary[i] ? Eigen::RowVector3d(sphere.row(i))
                           : Eigen::RowVector3d((m.vertices.row(i) - c) / std::max(r, 1e-300));
  SolverStats st;
  try {
    ps.options() = harmonic_solver_options(opt, ps.device(), m.num_tets());
    const FieldValues values = u;
    st = ps.solve_dirichlet(boundary, values, u);
  } catch (const NumericalError& e) {
    throw NumericalError(std::string("initial_map: the harmonic solve failed: ") + e.what() + "; " + note);
  }
  if (!u.allFinite()) throw NumericalError("initial_map: the harmonic solve gave non-finite positions; " + note);
  rep.harmonic_on_device = !ps.device().is_host();
  rep.harmonic_preconditioner = to_string(ps.options().preconditioner);
  rep.harmonic_iterations = st.iterations;
  rep.harmonic_relative_residual = st.relative_residual;
  Points ball = u;
  for (int i = 0; i < n; ++i)
    if (boundary[i]) ball.row(i) = sphere.row(i);
  return ball;
}

using detail::untangle_map;

void say(const InitialMapOptions& opt, const std::string& line) {
  if (opt.progress) opt.progress("initial map: " + line);
}

// A sphere map and the seconds it took.
struct TimedSphereMap {
  SphereMapResult map;
  double seconds = 0;
};

TimedSphereMap timed_sphere_map(const TriSurface& surf, const InitialMapOptions& opt, Device& device) {
  const auto t0 = Clock::now();
  TimedSphereMap r{sphere_map(surf, opt, &device), 0};
  r.seconds = seconds_since(t0);
  return r;
}

// Steps 2-4 on the refined mesh m (boundary surface surf, mask res.boundary): sphere map (or
// `early`, the same map made on the input's vertices while the split ran), harmonic interior,
// untangling (without its global run when `global` is false); fills res.ball and rep. False
// when the sphere map flipped a triangle or folds remain.
bool map_through_sphere(Device& device, const TetMesh& m, const TriSurface& surf, const InitialMapOptions& opt,
                        const std::string& note, InitialMapResult& res, InitialMapReport& rep,
                        std::future<std::shared_ptr<PoissonSolver>>& solver, TimedSphereMap* early = nullptr,
                        bool global = true) {
  TimedSphereMap tm = early ? std::move(*early) : timed_sphere_map(surf, opt, device);
  SphereMapResult& sm = tm.map;
  rep.boundary = sm.report;
  rep.timings.boundary = tm.seconds;
  say(opt, "sphere map: " + strprintf("%.2f s", tm.seconds) +
               (sm.flipped_triangles ? ", " + std::to_string(sm.flipped_triangles) + " triangles flipped" : ""));
  if (sm.flipped_triangles > 0) return false;
  if (sm.sphere.rows() < m.num_vertices()) {  // inserted (interior) vertices: rows as for unused ones
    const Eigen::Index k = sm.sphere.rows();
    sm.sphere.conservativeResize(m.num_vertices(), 3);
    sm.sphere.bottomRows(m.num_vertices() - k) = Eigen::RowVector3d(0, 0, 1).replicate(m.num_vertices() - k, 1);
  }

  auto t0 = Clock::now();
  if (!res.poisson) res.poisson = solver.get();
  res.ball = harmonic_interior(m, res.boundary, sm.sphere, opt, note, rep, *res.poisson);
  rep.folds_before_untangle = static_cast<int>(inverted_tets(res.ball, m.tets).size());
  rep.timings.harmonic = seconds_since(t0);
  say(opt, "harmonic interior: " + std::to_string(rep.harmonic_iterations) + " iterations, " +
               std::to_string(rep.folds_before_untangle) + " folds" + strprintf(", %.2f s", rep.timings.harmonic));

  t0 = Clock::now();
  rep.folds_after_untangle = untangle_map(device, m, res.boundary, opt, res.ball, rep, global);
  rep.timings.untangle = seconds_since(t0);
  if (rep.folds_before_untangle > 0 || rep.folds_after_untangle > 0)
    say(opt, "untangling: " + std::to_string(rep.folds_before_untangle) + " -> " +
                 std::to_string(rep.folds_after_untangle) + " folds" + strprintf(", %.2f s", rep.timings.untangle));
  rep.boundary_max_radius_error = 0;
  for (int i = 0; i < m.num_vertices(); ++i)  // boundary exactly on the sphere
    if (res.boundary[i])
      rep.boundary_max_radius_error = std::max(rep.boundary_max_radius_error, std::abs(res.ball.row(i).norm() - 1.0));
  return rep.folds_after_untangle == 0;
}

[[noreturn]] void throw_folded(const TetMesh& m, const Points& ball, const InitialMapReport& rep,
                               const std::string& note, bool budget_spent) {
  const std::vector<int> bad = inverted_tets(ball, m.tets);
  std::string where;
  for (size_t i = 0; i < bad.size() && i < 3; ++i) {
    const Eigen::Vector3d c = tet_centroid(m.vertices, m.tets, bad[i]);
    where += (i ? "; " : "") + std::string("tet ") + std::to_string(bad[i]) + " at (" + format_sig(c(0)) + ", " +
             format_sig(c(1)) + ", " + format_sig(c(2)) + ")";
  }
  throw NumericalError("initial_map: " + std::to_string(bad.size()) + " tets remain folded after untangling" +
                       (budget_spent ? " cut short by the time budget" : "") + " (harmonic map folded " +
                       std::to_string(rep.folds_before_untangle) + "): " + where + "; " + note);
}

// The conformal redo crowded a thin part, or there is none after an axial start: the equal-area
// attempt `area` is kept (res) and untangled with the global run that its local runs did not try
// (InitialMapReport::Fallback::crowded, ::axial).
void untangle_globally(Device& device, const TetMesh& m, const InitialMapOptions& opt, InitialMapResult area,
                       InitialMapResult& res, const char* why) {
  say(opt, std::string(why) + ": the equal-area attempt, untangled globally");
  res = std::move(area);
  InitialMapReport& rep = res.report;
  const auto t0 = Clock::now();
  rep.folds_after_untangle = untangle_map(device, m, res.boundary, opt, res.ball, rep, true, true);
  rep.timings.untangle += seconds_since(t0);
}

// Untangling from the equal-area boundary left folds: steps 2-4 again from the conformal sphere
// map (a flipped sphere map would flip the same way: the flow never flips), unless it crowds a
// thin part, decided from its boundary alone where the bound settles it, or the automatic
// start chose the axial map, which it keeps only where the conformal one flips or crowds
// (InitialMapReport::Fallback). A start named in the options is redone without the area flow
// (the sphere map's start stays the named one).
constexpr const char* kCrowds = "the conformal sphere map crowds a thin part";

void conformal_fallback(Device& device, const TetMesh& m, const TriSurface& surf, const InitialMapOptions& opt,
                        const std::string& note, InitialMapResult& res,
                        std::future<std::shared_ptr<PoissonSolver>>& solver) {
  InitialMapReport& rep = res.report;
  InitialMapReport::Fallback fb;
  fb.axial = rep.boundary.start == "axial" && opt.sphere_start == InitialMapOptions::SphereStart::automatic;
  say(opt, std::to_string(rep.folds_after_untangle) + " folds left" +
               (fb.axial ? "" : ": again from the conformal sphere map"));
  fb.from = to_string(opt.sphere_density);
  fb.flipped_triangles = rep.boundary.flipped_triangles;
  fb.folds_after_untangle = rep.folds_after_untangle;
  fb.seconds = rep.timings.boundary + rep.timings.harmonic + rep.timings.untangle;
  InitialMapOptions conformal = opt;
  conformal.sphere_density = InitialMapOptions::SphereDensity::conformal;
  rep.untangle_local_failed.reset();
  rep.untangle_cleanup.reset();
  rep.untangle_slide.reset();
  InitialMapResult area = res;  // with its local runs' report, which its global run follows
  rep.untangle.reset();
  std::optional<TimedSphereMap> redo;
  if (!fb.axial) redo = timed_sphere_map(surf, conformal, device);
  if (redo && redo->map.flipped_triangles == 0) {
    fb.conformal_min_tet_ratio = boundary_tet_ratio_bound(m, redo->map.sphere);
    fb.crowded_by_boundary = fb.conformal_min_tet_ratio < InitialMapReport::kCrowdedRatio;
  }
  if (fb.axial || fb.crowded_by_boundary) {
    fb.crowded = fb.crowded_by_boundary;
    untangle_globally(device, m, opt, std::move(area), res, fb.axial ? "an axial start has no conformal redo" : kCrowds);
  } else {
    map_through_sphere(device, m, surf, conformal, note, res, rep, solver, &*redo);
    fb.conformal_min_tet_ratio = map_metrics(device, m.vertices, res.ball, m.tets).tet_volume_ratio.min;
    fb.crowded = rep.boundary.flipped_triangles == 0 && fb.conformal_min_tet_ratio < InitialMapReport::kCrowdedRatio;
    if (fb.crowded) untangle_globally(device, m, opt, std::move(area), res, kCrowds);
  }
  rep.fallback = fb;
}

}  // namespace

InitialMapResult initial_map(Device& device, const TetMesh& input, const InitialMapOptions& opt) {
  const auto t_total = Clock::now();
  InitialMapResult res;
  InitialMapReport& rep = res.report;
  rep.device = device.name();
  rep.input_vertices = input.num_vertices();
  rep.input_tets = input.num_tets();
  check_input(input);
  auto t0 = Clock::now();
  measure_quality(input, opt.report_worst_tets, rep);
  const std::string note = quality_note(input, rep);
  rep.timings.input_quality = seconds_since(t0);

  // The sphere map needs only the boundary surface, which the split does not change (it inserts
  // interior vertices after the input's): it runs on a second thread while the split runs.
  t0 = Clock::now();
  const Triangles input_boundary = boundary_faces(input.tets);
  std::future<TimedSphereMap> early_sphere = std::async(std::launch::async, [&] {
    return timed_sphere_map(TriSurface{input.vertices, input_boundary}, opt, device);
  });
  SplitResult sp = split(input, input_boundary, opt, rep);
  res.mesh = std::move(sp.mesh);
  const TetMesh& m = res.mesh;
  rep.timings.split = seconds_since(t0);
  say(opt, "split: " + std::to_string(res.mesh.num_vertices()) + " vertices, " + std::to_string(res.mesh.num_tets()) +
               strprintf(" tets, %.2f s", rep.timings.split));

  TriSurface surf;
  surf.vertices = m.vertices;
  surf.triangles = std::move(sp.boundary);
  res.boundary = boundary_vertex_mask(m.num_vertices(), surf.triangles);
  // the Poisson solver is built on a third thread, also while a sphere map solves on the device
  // (Device::kernel is thread-safe, kernels are never shared, and neither uses Boost.Compute's
  // kernel-generating algorithms, whose program cache is not)
  std::future<std::shared_ptr<PoissonSolver>> solver = start_harmonic_solver(device, m, opt);
  TimedSphereMap early = early_sphere.get();
  // with a fallback to come, the first attempt untangles locally only (untangle_map)
  const bool can_fall_back = opt.sphere_density != InitialMapOptions::SphereDensity::conformal;
  const bool done = map_through_sphere(device, m, surf, opt, note, res, rep, solver, &early, !can_fall_back);
  if (!done && rep.boundary.flipped_triangles == 0 && !opt.deadline.passed() && can_fall_back)
    conformal_fallback(device, m, surf, opt, note, res, solver);
  if (rep.folds_after_untangle > 0 && rep.boundary.flipped_triangles == 0)
    say(opt, std::to_string(rep.folds_after_untangle) + " folds left: refining around them");
  if (rep.boundary.flipped_triangles == 0 && detail::refine_folds(device, surf.triangles, opt, res, rep))
    res.poisson = start_harmonic_solver(device, res.mesh, opt).get();  // on the refined tets
  if (rep.boundary.flipped_triangles > 0)
    throw NumericalError("initial_map: the boundary map to the sphere flipped " +
                         std::to_string(rep.boundary.flipped_triangles) + " of " +
                         std::to_string(surf.triangles.rows()) + " triangles; " + note);
  if (rep.folds_after_untangle > 0 && opt.throw_on_folds) throw_folded(m, res.ball, rep, note, opt.deadline.passed());

  t0 = Clock::now();
  rep.metrics = map_metrics(device, m.vertices, res.ball, m.tets, &res.boundary);
  rep.timings.metrics = seconds_since(t0);
  rep.timings.total = seconds_since(t_total);
  return res;
}

}  // namespace vpm
