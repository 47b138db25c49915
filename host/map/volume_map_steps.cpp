// The steps of the volume-preserving map's rounds (map/volume_map_context.hpp).
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "map/volume_map_context.hpp"
#include "vpm/device.hpp"
#include "vpm/geometry.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"

namespace vpm::detail {

DeviceAdvector& MapContext::device_advector() const {
  if (!advector || !advector->on_device())
    throw std::logic_error("volume map: the field's gradients were placed on a device without its advection");
  return static_cast<DeviceAdvector&>(*advector);
}

int count_folds(MapContext& c, const Points& x) {
  const Eigen::VectorXd v = c.volumes->tet_volumes(x);
  return static_cast<int>((v.array() <= 0).count());
}

namespace {

std::vector<int> folded_list(const Points& x, const Tets& tets) {
  const Eigen::VectorXd v = tet_volumes(x, tets);
  std::vector<int> out;
  for (Eigen::Index t = 0; t < v.size(); ++t)
    if (v(t) <= 0) out.push_back(static_cast<int>(t));
  return out;
}

}  // namespace

// Local untangling of the folded tets of x (boundary fixed; when sliding and `before` is given,
// boundary triangles flipped on the sphere are unflipped first). Returns the folds left.
int untangle_folds(MapContext& c, Points& x, double* seconds, const Points* before) {
  const auto t0 = Clock::now();
  std::vector<int> folded = folded_list(x, c.tets);
  if (folded.empty()) return 0;
  if (c.opt.local_untangle && c.slide && before) {
    unflip_sphere_faces(*before, c.bfaces, x, c.pc.pinned);
    folded = folded_list(x, c.tets);
  }
  if (c.opt.local_untangle) {
    for (int rings = 2; rings <= 4 && !folded.empty(); rings += 2) {
      untangle_local(c.ref, c.tets, x, c.frozen, folded, rings, untangle_local_options());
      folded = folded_list(x, c.tets);
    }
  }
  if (seconds) *seconds += seconds_since(t0);
  return static_cast<int>(folded.size());
}

namespace {

// Dual volumes, targets rescaled to the current total, rho0 = m / V, and the Neumann solve
// K psi = m - V. Returns V and m.
void solve_round(MapContext& c, const Points& x, Eigen::VectorXd& V, Eigen::VectorXd& target,
                 VolumeMapRound& r) {
  const auto t0 = Clock::now();
  V = c.volumes->dual_volumes(x);
  target = c.ref_dual * V.sum();
  const Eigen::VectorXd b = target - V;
  c.psi.setZero(c.n);
  const detail::SolveStats s = c.solver->neumann(x, b, c.psi);
  r.solver_iterations += s.iterations;
  r.solver_residual = std::max(r.solver_residual, s.residual);
  r.time_solve += seconds_since(t0);
}

// The solve of a round and its field on the background x: f's grid, and its inverse matrices
// and vertex gradients on the host unless `gradients_on_device` (the advector makes both).
void solve_and_field(MapContext& c, const Points& x, Eigen::VectorXd& V, Eigen::VectorXd& target,
                     detail::MoserField& f, VolumeMapRound& r, bool gradients_on_device = false) {
  solve_round(c, x, V, target, r);
  const auto t1 = Clock::now();
  if (gradients_on_device) {
    detail::build_grid(f, x, c.tets, c.nbr);
  } else {
    detail::build_background(f, x, c.tets, c.nbr);
    const auto G = detail::tet_gradients(f, c.psi);
    const Eigen::VectorXd vol = tet_volumes(x, c.tets);
    f.grad = detail::vertex_gradients(c.tets, x, G, vol, c.boundary, c.slide);
  }
  r.time_field += seconds_since(t1);
}

}  // namespace

// One Moser round on [0, t_end]: x in/out. With gradients_on_device the field's gradients are
// computed where the advection runs, from psi.
void moser_round(MapContext& c, Points& x, double t_end, VolumeMapRound& r) {
  Eigen::VectorXd V, target;
  // the context's field: its big arrays keep their memory from round to round (rebuilt in place,
  // no fresh pages; MapContext::field)
  detail::MoserField& f = c.field;
  // the advector reads f's arrays in place (the host's, CPU devices'): they are released after
  // the round, even on an exception
  struct ReleaseField {
    Advector* advector;
    ~ReleaseField() {
      if (advector) advector->release_field();
    }
  } release{c.advector.get()};
  solve_and_field(c, x, V, target, f, r, c.gradients_on_device);
  const auto t1 = Clock::now();
  f.rho0.resize(static_cast<size_t>(c.n));
  for (int i = 0; i < c.n; ++i) f.rho0[i] = V(i) > 0 ? target(i) / V(i) : 1.0;
  if (c.gradients_on_device) c.device_advector().set_field(f, c.psi, x, c.slide);
  else c.advector->set_field(f);  // the host's and CPU devices' read f's arrays in place: f stays
  r.time_field += seconds_since(t1);

  const auto t2 = Clock::now();
  detail::AdvectParams p;
  p.steps = std::max(1, c.opt.rk_steps);
  p.t_end = t_end;
  p.slide = c.slide;
  std::vector<int> hint = c.vertex_tet;
  detail::AdvectStats st;
  c.advector->advect(p, x, hint, &st);
  r.time_advect += seconds_since(t2);
  r.walk_steps_per_location = st.locations ? double(st.walk_steps) / double(st.locations) : 0.0;
  r.grid_fallbacks += st.grid_fallbacks;
  r.clamped += st.clamped;
}

// The paper's explicit step: re-solve on the current geometry, x += dt grad psi / rho.
void paper_step(MapContext& c, Points& x, double dt, VolumeMapRound& r) {
  Eigen::VectorXd V, target;
  detail::MoserField f;
  solve_and_field(c, x, V, target, f, r);
  const std::vector<double>& g = f.grad;
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

// Polish: one Gauss-Newton direction on the relative tet volumes (map/polish.hpp).
void polish_step(MapContext& c, const Points& x, VolumeMapRound& r, Points& dx_out, int iterations) {
  const auto t0 = Clock::now();
  const Eigen::VectorXd vol = tet_volumes(x, c.tets);
  const Eigen::VectorXd target = c.ref_tet * vol.sum();
  if (c.freedom.empty()) c.freedom = detail::polish_freedom(c.boundary, c.slide, c.pc.pinned);
  if (!c.polisher)
    c.polisher = detail::make_polisher(c.dev, c.polish_on_device, c.tets, c.n, c.freedom, c.pc.anchors, c.pc.holds);
  detail::PolishDirection d = c.polisher->direction(x, target, iterations);
  r.solver_iterations += d.iterations;
  r.solver_residual = d.residual;
  r.time_solve += seconds_since(t0);
  dx_out = std::move(d.dx);
}

void project_boundary(const MapContext& c, Points& x) {
  if (!c.slide) return;
  for (int i = 0; i < c.n; ++i)
    if (c.boundary[i] && !c.pinned(i)) x.row(i).normalize();
}

}  // namespace vpm::detail
