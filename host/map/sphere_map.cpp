// Step 2 of the initial map (vpm/initial_map.hpp): the boundary surface to the unit sphere by a
// spherical conformal map (planar harmonic map, inverse stereographic projection, south-pole
// correction), orientation check and Moebius balancing, or the progressive embedding where that
// flips or stays crowded; then the area equalisation and optional area correction. The report's
// JSON and the options' names: map/sphere_map_report.cpp.
#include "vpm/initial_map.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <numeric>
#include <set>
#include <string>
#include <utility>
#include <Eigen/SparseCholesky>
#include <Eigen/IterativeLinearSolvers>
#include <complex>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "map/sphere_steps.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"

namespace vpm {


double area_distortion(const Points& in, const Points& sp, const Triangles& f) {
  const Eigen::Index k = f.rows();
  if (k == 0) return 0;
  Eigen::VectorXd a(k), b(k);
  for (Eigen::Index i = 0; i < k; ++i) {
    const Eigen::Vector3d p0 = in.row(f(i, 0)), p1 = in.row(f(i, 1)), p2 = in.row(f(i, 2));
    const Eigen::Vector3d q0 = sp.row(f(i, 0)), q1 = sp.row(f(i, 1)), q2 = sp.row(f(i, 2));
    a(i) = 0.5 * (p1 - p0).cross(p2 - p0).norm();
    b(i) = 0.5 * (q1 - q0).cross(q2 - q0).norm();
  }
  const double sa = a.sum(), sb = b.sum();
  double s = 0;
  for (Eigen::Index i = 0; i < k; ++i) s += std::abs((b(i) / sb) / std::max(a(i) / sa, 1e-300) - 1.0);
  return s / static_cast<double>(k);
}

int flipped_sphere_triangles(const Points& sp, const Triangles& f) {
  int c = 0;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const Eigen::Vector3d a = sp.row(f(i, 0)), b = sp.row(f(i, 1)), d = sp.row(f(i, 2));
    if (!(a.dot(b.cross(d)) > 0)) ++c;
  }
  return c;
}

using namespace detail;

namespace {

// The surface with only the vertices its triangles use (step 2 works on those).
struct CompactSurface {
  Points in;            // k x 3 positions
  Triangles f;          // triangles over 0..k-1
  std::vector<int> used;  // surface vertex of each compact vertex
};

CompactSurface compact(const TriSurface& surf) {
  CompactSurface c;
  const int nall = static_cast<int>(surf.vertices.rows());
  std::vector<int> loc(nall, -1);
  for (Eigen::Index i = 0; i < surf.triangles.rows(); ++i)
    for (int k = 0; k < 3; ++k) {
      const int v = surf.triangles(i, k);
      if (v < 0 || v >= nall) throw InputError("sphere_map: triangle " + std::to_string(i) + " has vertex index out of range");
      if (loc[v] < 0) {
        loc[v] = static_cast<int>(c.used.size());
        c.used.push_back(v);
      }
    }
  const int k = static_cast<int>(c.used.size());
  c.f.resize(surf.triangles.rows(), 3);
  for (Eigen::Index i = 0; i < c.f.rows(); ++i)
    for (int j = 0; j < 3; ++j) c.f(i, j) = loc[surf.triangles(i, j)];
  c.in.resize(k, 3);
  for (int i = 0; i < k; ++i) c.in.row(i) = surf.vertices.row(c.used[i]);
  const SurfaceTopology topo = surface_topology(k, c.f);
  if (topo.components != 1 || topo.open_edges || topo.nonmanifold_edges || topo.nonmanifold_vertices ||
      topo.euler != 2)
    throw InputError("sphere_map: the boundary is not one closed genus-0 surface (euler " +
                     std::to_string(topo.euler) + ", components " + std::to_string(topo.components) +
                     ", open edges " + std::to_string(topo.open_edges) + ")");
  return c;
}

// The most regular triangle (edge lengths closest to equal): the north-pole cap of the map.
Eigen::Index most_regular_triangle(const Points& in, const Triangles& f) {
  Eigen::Index big = 0;
  double best = 1e300;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const double e1 = (in.row(f(i, 1)) - in.row(f(i, 2))).norm();
    const double e2 = (in.row(f(i, 2)) - in.row(f(i, 0))).norm();
    const double e3 = (in.row(f(i, 0)) - in.row(f(i, 1))).norm();
    const double s = e1 + e2 + e3;
    const double reg = std::abs(e1 / s - 1.0 / 3) + std::abs(e2 / s - 1.0 / 3) + std::abs(e3 / s - 1.0 / 3);
    if (reg < best) {
      best = reg;
      big = i;
    }
  }
  return big;
}

// The planar harmonic map of the surface minus triangle `big` onto the plane (big's corners
// fixed at a similar triangle), scaled so the north and south caps have comparable sizes,
// projected to the sphere. False when the planar solve failed (s unchanged).
bool planar_to_sphere(const Points& in, const Triangles& f, Eigen::Index big, double clamp, Points& out) {
  const int k = static_cast<int>(in.rows());
  const int p1 = f(big, 0), p2 = f(big, 1), p3 = f(big, 2);
  const Eigen::Vector3d ea = in.row(p2) - in.row(p1), eb = in.row(p3) - in.row(p1);
  const double ratio = 1.0 / ea.norm();
  const double sin1 = ea.cross(eb).norm() / (ea.norm() * eb.norm());
  std::vector<char> fixed(k, 0);
  fixed[p1] = fixed[p2] = fixed[p3] = 1;
  Eigen::MatrixXd z = Eigen::MatrixXd::Zero(k, 2);
  z.row(p1) << 0, 0;
  z.row(p2) << 1, 0;
  z.row(p3) << ea.dot(eb) / ea.norm() * ratio, eb.norm() * sin1 * ratio;
  if (!dirichlet_solve(cot_laplacian(in, f, clamp), fixed, z)) return false;
  const Eigen::RowVector2d mean = z.colwise().mean();
  z.rowwise() -= mean;
  // rescale so the north (big) and south (innermost) triangles have comparable sizes
  const Points s = inverse_stereo_north(z);
  Eigen::Index inner = -1;
  double innermost = 1e300;
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    if (i == big) continue;
    const double d = z.row(f(i, 0)).norm() + z.row(f(i, 1)).norm() + z.row(f(i, 2)).norm();
    if (d < innermost) {
      innermost = d;
      inner = i;
    }
  }
  auto side = [&](const Eigen::MatrixXd& q, Eigen::Index t) {
    return ((q.row(f(t, 0)) - q.row(f(t, 1))).norm() + (q.row(f(t, 1)) - q.row(f(t, 2))).norm() +
            (q.row(f(t, 2)) - q.row(f(t, 0))).norm()) / 3;
  };
  Eigen::MatrixXd w(k, 2);
  for (int i = 0; i < k; ++i) w.row(i) << s(i, 0) / (1 + s(i, 2)), s(i, 1) / (1 + s(i, 2));
  const double north = side(z, big), south = side(w, inner);
  if (north > 0 && south > 0 && std::isfinite(south)) z *= std::sqrt(north * south) / north;
  out = inverse_stereo_north(z);
  return true;
}

// Step 2.1: the spherical conformal map, cotangent weights first, clamped ones if that flips
// triangles; the mirror image is taken when it flips fewer. Sets *flips (all triangles when no
// solve succeeded; then the returned points are empty).
Points conformal_sphere(const Points& in, const Triangles& f, SphereMapReport& rep, int* flips) {
  const Eigen::Index big = most_regular_triangle(in, f);
  Points s;
  rep.planar_weights = "cotangent";
  for (int attempt = 0; attempt < 2; ++attempt) {
    if (!planar_to_sphere(in, f, big, attempt == 0 ? 0.0 : 1e-3, s)) {
      *flips = static_cast<int>(f.rows());
      continue;
    }
    *flips = flipped_sphere_triangles(s, f);
    if (s.allFinite()) {
      // the disk may be mirrored (the big triangle is the complement cap, not part of it)
      Points m = s;
      m.col(0) *= -1;
      const int flips_m = flipped_sphere_triangles(m, f);
      if (flips_m < *flips) {
        s = m;
        *flips = flips_m;
      }
      if (*flips == 0) break;
    }
    rep.planar_weights = "clamped cotangent";
  }
  rep.flipped_after_conformal = *flips;
  return s;
}

// Step 2.2: the south-pole correction, kept when it flips no more triangles.
void correct_south_pole(const Points& in, const Triangles& f, Points& s, int* flips, SphereMapReport& rep) {
  Points c = s;
  rep.south_pole_correction = false;
  if (!south_pole_correction(in, f, c)) return;
  Points m = c;  // orientation may differ: the correction works in the south-pole chart
  m.col(0) *= -1;
  int fc = flipped_sphere_triangles(c, f);
  const int fm = flipped_sphere_triangles(m, f);
  if (fm < fc) {
    c = m;
    fc = fm;
  }
  rep.flipped_after_south_pole = fc;
  if (fc <= *flips) {
    s = c;
    *flips = fc;
    rep.south_pole_correction = true;
  }
}

// Step 2.4: Moebius balancing with the input vertex areas, kept when it flips nothing new and
// does not raise the area distortion (elongated shapes can be better off unbalanced).
void balance(const Points& in, const Triangles& f, const InitialMapOptions& opt, Points& s, int* flips,
             SphereMapReport& rep) {
  Eigen::VectorXd wv = Eigen::VectorXd::Zero(in.rows());
  for (Eigen::Index i = 0; i < f.rows(); ++i) {
    const Eigen::Vector3d q0 = in.row(f(i, 0)), q1 = in.row(f(i, 1)), q2 = in.row(f(i, 2));
    const double a = 0.5 * (q1 - q0).cross(q2 - q0).norm() / 3;
    for (int c = 0; c < 3; ++c) wv(f(i, c)) += a;
  }
  Points b = s;
  double cn = 0;
  rep.moebius_iterations = moebius_balance(wv, b, opt.moebius_max_iterations, opt.moebius_tolerance, &cn);
  const int fb = flipped_sphere_triangles(b, f);
  rep.moebius_centroid_norm = cn;
  const double before = area_distortion(in, s, f), after = area_distortion(in, b, f);
  rep.area_distortion_balanced = after;
  rep.moebius_kept = fb <= *flips && after <= before;
  if (rep.moebius_kept) {
    s = b;
    *flips = fb;
  }
}

// Step 2.5: area equalisation, kept when it brings the sphere areas closer to the input's
// shares without a flip.
void equalise(const Points& in, const Triangles& f, const InitialMapOptions& opt, Points& s, SphereMapReport& rep,
              Device* device) {
  rep.density_target = "area";
  const auto t0 = Clock::now();
  Points q = s;
  Device* solve_on = nullptr;
  if (device && rep.placement.decide(*device, PlacedWork::density_solve, opt.density_solve, in.rows()))
    solve_on = device;
  const EquiarealStats st = equalise_density(in, f, vertex_area_shares(in, f), q, opt.density_max_steps,
                                             opt.density_tolerance, solve_on);
  rep.density_solver = st.solver;
  rep.seconds_density_solve = st.solve_seconds;
  rep.density_steps = st.steps;
  rep.density_misfit_before = st.misfit_before;
  rep.density_misfit_after = st.misfit_after;
  rep.area_distortion_density = st.distortion_after;
  rep.density_kept = st.steps > 0 && st.misfit_after < st.misfit_before && flipped_sphere_triangles(q, f) == 0;
  if (rep.density_kept) s = std::move(q);
  rep.seconds_density = seconds_since(t0);
}

// The progressive embedding (map/sphere_steps.hpp) as the start; its statistics go to `rep`.
Points progressive_start(const Points& in, const Triangles& f, SphereMapReport& rep) {
  ProgressiveStats ps;
  Points s = progressive_sphere(in, f, &ps);
  rep.start = "progressive";
  rep.progressive_passes = ps.passes;
  rep.progressive_collapses = ps.collapses;
  rep.progressive_sweeps = ps.sweeps;
  rep.progressive_seconds = ps.seconds;
  return s;
}

// The log misfit the area equalisation left (the start's when it was not kept).
double misfit_left(const SphereMapReport& rep) {
  return rep.density_kept ? rep.density_misfit_after : rep.density_misfit_before;
}

// The conformal start (steps 2.1-2.4); returns the chord triangles facing inwards.
int conformal_start(const Points& in, const Triangles& f, const InitialMapOptions& opt, Points& s,
                    SphereMapReport& rep) {
  const auto t0 = Clock::now();
  int flips = 0;
  s = conformal_sphere(in, f, rep, &flips);
  if (opt.south_pole_correction && s.allFinite()) correct_south_pole(in, f, s, &flips, rep);
  normalize_rows(s);
  // 3. orientation: outward faces must have det > 0 in the majority (total signed volume > 0)
  double vol = 0;
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    vol += Eigen::Vector3d(s.row(f(i, 0))).dot(Eigen::Vector3d(s.row(f(i, 1))).cross(Eigen::Vector3d(s.row(f(i, 2)))));
  rep.mirrored = vol < 0;
  if (vol < 0) s.col(0) *= -1;
  rep.area_distortion_conformal = area_distortion(in, s, f);
  rep.seconds_conformal = seconds_since(t0);
  const auto t1 = Clock::now();
  if (opt.moebius_balance) balance(in, f, opt, s, &flips, rep);
  rep.seconds_moebius = seconds_since(t1);
  return flipped_sphere_triangles(s, f);
}

// The axial map (map/sphere_steps.hpp) as the start, its statistics in `rep`; empty when it
// failed or a chord triangle faces inwards.
Points axial_start(const Points& in, const Triangles& f, SphereMapReport& rep) {
  AxialStats as;
  Points s = axial_sphere(in, f, &as);
  if (s.rows() == 0 || flipped_sphere_triangles(s, f) > 0) return Points();
  rep.start = "axial";
  rep.axial_seconds = as.seconds;
  return s;
}

// The start and its area equalisation: the conformal start, or the progressive and the axial
// ones where the conformal start flips triangles or stays crowded after its equalisation
// (SphereMapReport::kCrowdedMisfit: limbs shrunk below what the flow recovers); of the
// equalised starts the one with the smallest log misfit. `sphere_start` can name one.
Points equalised_start(const Points& in, const Triangles& f, const InitialMapOptions& opt, SphereMapReport& rep,
                       Device* device) {
  using Start = InitialMapOptions::SphereStart;
  const bool automatic = opt.sphere_start == Start::automatic;
  const bool equal_area = opt.sphere_density != InitialMapOptions::SphereDensity::conformal;
  Points s;
  const int flips = automatic ? conformal_start(in, f, opt, s, rep) : 0;
  const SphereMapReport started = rep;
  const bool compare = automatic && flips == 0;
  if (compare) {
    if (equal_area) equalise(in, f, opt, s, rep, device);
    if (!equal_area || misfit_left(rep) <= SphereMapReport::kCrowdedMisfit) return s;
  }
  // the axial start (equal-area bands) where the areas are to be equalised
  SphereMapReport ax = started;
  Points x = (automatic && equal_area) || opt.sphere_start == Start::axial ? axial_start(in, f, ax) : Points();
  if (x.rows() > 0 && equal_area) equalise(in, f, opt, x, ax, device);
  if (opt.sphere_start == Start::axial && x.rows() > 0) {
    rep = ax;
    return x;
  }
  SphereMapReport alt = started;
  Points p = progressive_start(in, f, alt);
  const bool folded = flipped_sphere_triangles(p, f) > 0;
  if (equal_area && !folded) equalise(in, f, opt, p, alt, device);
  if (!automatic) {
    rep = alt;
    return p;
  }
  std::optional<double> conformal, progressive, axial;
  if (compare) conformal = misfit_left(rep);
  if (!folded) progressive = misfit_left(alt);
  if (x.rows() > 0) axial = misfit_left(ax);
  for (SphereMapReport* r : {&rep, &alt, &ax}) {
    r->conformal_log_misfit = conformal;
    r->progressive_log_misfit = progressive;
    r->axial_log_misfit = axial;
  }
  const double inf = std::numeric_limits<double>::infinity();
  const double mc = conformal.value_or(inf), mp = progressive.value_or(inf), ma = axial.value_or(inf);
  if (compare && mc <= mp && mc <= ma) return s;
  if (axial && ma < mp) {
    rep = ax;
    return x;
  }
  if (folded && compare) return s;
  rep = alt;
  return p;
}

}  // namespace

SphereMapResult sphere_map(const TriSurface& surf, const InitialMapOptions& opt) { return sphere_map(surf, opt, nullptr); }

SphereMapResult sphere_map(const TriSurface& surf, const InitialMapOptions& opt, Device* device) {
  SphereMapResult r;
  SphereMapReport& rep = r.report;
  const CompactSurface cs = compact(surf);
  const Points& in = cs.in;
  const Triangles& f = cs.f;
  rep.vertices = static_cast<int>(in.rows());
  rep.faces = static_cast<int>(f.rows());
  Points s = equalised_start(in, f, opt, rep, device);
  if (opt.area_correction) rep.area_correction_steps = area_flow(in, f, s, opt.area_correction_steps, false);
  if (flipped_sphere_triangles(s, f) > 0) {
    // Extreme conformal scale factors (protrusions, coarse elongated shapes) can make a chord
    // triangle face inwards: spread the areas until none does.
    rep.flipped_before_repair = flipped_sphere_triangles(s, f);
    rep.repair_steps = area_flow(in, f, s, std::max(opt.area_correction_steps, 100), true);
  }
  normalize_rows(s);
  const int flips = flipped_sphere_triangles(s, f);
  rep.area_distortion_final = area_distortion(in, s, f);
  rep.flipped_triangles = flips;
  r.flipped_triangles = flips;
  r.sphere = Points::Zero(surf.vertices.rows(), 3);
  r.sphere.col(2).setOnes();
  for (size_t i = 0; i < cs.used.size(); ++i) r.sphere.row(cs.used[i]) = s.row(static_cast<Eigen::Index>(i));
  return r;
}

}  // namespace vpm
