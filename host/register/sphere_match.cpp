// The dense iterations of a registration on the sphere (sphere_match.hpp): smoothed, standardised
// scalars, the template's located at the subject's vertices, Gauss-Newton steps of a
// surface-divergence-free Gaussian field with its centres on an icosphere, coarse to fine.
#include "register/sphere_match.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "map/surface_area.hpp"
#include "register/dense_surface.hpp"
#include "register/point_bins.hpp"
#include "register/sphere_field.hpp"
#include "register/sphere_rotation.hpp"
#include "register/sphere_step.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

// The icosphere level whose edges (about 1.05 / 2^level) are at most `width`.
int centre_level(double width) {
  int level = 0;
  while (level < 6 && 1.05 / std::ldexp(1.0, level) > width) ++level;
  return level;
}

// A scalar of the sphere's vertices `x` smoothed at scale sigma (chord length): the
// area-weighted Gaussian average sum_j a_j k(x - x_j) f_j / sum_j a_j k(x - x_j),
// k(r) = exp(-|r|^2 / (2 sigma^2)) over the vertices within 3 sigma, evaluated at the nodes of an
// icosphere of spacing at most sigma / 2 and interpolated from them (the average varies on the
// scale sigma): independent of how the surface is triangulated, at a cost set by sigma.
Eigen::VectorXd smooth(const Points& x, const Eigen::VectorXd& values, const Eigen::VectorXd& area,
                       double sigma) {
  const TriSurface nodes = icosphere(centre_level(sigma / 2));
  const Eigen::VectorXd at = gaussian_average(x, values, area, sigma, static_cast<int>(nodes.vertices.rows()),
                                              [&](int i) { return Vector3d(nodes.vertices.row(i).transpose()); });
  const SphereLocator locator(nodes.vertices, nodes.triangles);
  const std::vector<SphereLocation> loc = locator.locate_all(x);
  Eigen::VectorXd out(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    const SphereLocation& l = loc[static_cast<size_t>(i)];
    out(i) = 0;
    for (int k = 0; k < 3; ++k) out(i) += l.bary[k] * at(nodes.triangles(l.face, k));
  }
  return out;
}

// The template at one level: its smoothed, standardised scalar, per-vertex tangent gradients,
// and the locator of its sphere.
struct TemplateLevel {
  const SphereLocator* locator = nullptr;
  Eigen::VectorXd g;
  std::vector<Vector3d> grad;
};

std::vector<Vector3d> vertex_gradients(const Points& y, const Triangles& f, const Eigen::VectorXd& g) {
  std::vector<Vector3d> grad(static_cast<size_t>(y.rows()), Vector3d::Zero());
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Vector3d a = y.row(f(t, 0)).transpose(), b = y.row(f(t, 1)).transpose(), c = y.row(f(t, 2)).transpose();
    const Vector3d n2 = (b - a).cross(c - a);  // 2 A n
    const double a2 = n2.squaredNorm();
    if (!(a2 > 0)) continue;
    // grad of the linear interpolant: sum_k g_k (n x e_k) / (2A), e_k the edge opposite corner k
    const Vector3d gf = (g(f(t, 0)) * n2.cross(c - b) + g(f(t, 1)) * n2.cross(a - c) + g(f(t, 2)) * n2.cross(b - a)) / a2;
    const double area = std::sqrt(a2) / 2;
    for (int k = 0; k < 3; ++k) grad[static_cast<size_t>(f(t, k))] += area * gf;
  }
  for (Eigen::Index i = 0; i < y.rows(); ++i) {
    const Vector3d p = y.row(i).transpose().normalized();
    Vector3d& v = grad[static_cast<size_t>(i)];
    v -= p * p.dot(v);
  }
  // area-weighted mean: divide by the vertex's share (3 x its dual area)
  const Eigen::VectorXd va = vertex_areas(y, f);
  for (Eigen::Index i = 0; i < y.rows(); ++i)
    if (va(i) > 0) grad[static_cast<size_t>(i)] /= 3 * va(i);
  return grad;
}

// The residuals e_i = g(x_i) - f_i and the gradients of g at x_i (tangent there); `hint` the
// faces located last (updated).
void sample(const TemplateLevel& tl, const std::vector<Vector3d>& x, const Eigen::VectorXd& f, std::vector<int>& hint,
            Eigen::VectorXd& e, std::vector<Vector3d>* grad) {
  const int n = static_cast<int>(x.size());
  e.resize(n);
  if (grad) grad->resize(x.size());
  const Triangles& tf = tl.locator->faces();
  parallel_for(n, 1024, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      const SphereLocation loc = tl.locator->locate(x[i], hint[i]);
      hint[i] = loc.face;
      double g = 0;
      Vector3d d = Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const int v = tf(loc.face, k);
        g += loc.bary[k] * tl.g(v);
        d += loc.bary[k] * tl.grad[static_cast<size_t>(v)];
      }
      e(i) = g - f(i);
      if (grad) (*grad)[i] = d - x[i] * x[i].dot(d);
    }
  });
}

// One level: the scalars smoothed at smoothing x width, the centres on an icosphere, at most
// options.iterations Gauss-Newton steps.
SphereMatchLevel match_level(Device& device, std::vector<Vector3d>& x, std::vector<Vector3d>& carried, const Points& reference,
                             const Triangles& faces, const Eigen::VectorXd& values, const SphereTemplate& templ,
                             const SphereLocator& locator, const Eigen::VectorXd& area, const Eigen::VectorXd& tarea,
                             double width, const SphereMatchOptions& options, const SurfaceDomainMoves& domain,
                             std::vector<int>& hint) {
  SphereMatchLevel lv;
  lv.width = width;
  const double sigma = options.smoothing * width, lambda = 1 / (width * width);
  const Eigen::VectorXd f = standardise(smooth(reference, values, area, sigma), area, "subject");
  TemplateLevel tl{&locator, standardise(smooth(templ.sphere, templ.values, tarea, sigma), tarea, "template"), {}};
  tl.grad = vertex_gradients(templ.sphere, templ.faces, tl.g);
  const Centres cs(icosphere(centre_level(width)).vertices, width);
  lv.centres = cs.size();
  const Eigen::SparseMatrix<double> K = centre_gram(cs);
  Eigen::VectorXd e;
  std::vector<Vector3d> grad;
  sample(tl, x, f, hint, e, &grad);
  double E = lv.mismatch_before = mismatch(e, area);
  const size_t flipped = domain.flipped(to_matrix(x), faces).size();  // the step may not add any
  for (int it = 0; it < options.iterations; ++it) {
    const BinnedField field = gauss_newton_field(system_rows(x, grad, carried, cs), area, e, K, cs, options.ridge);
    const double speed = max_speed(x, field);
    if (!(speed > 0)) break;
    double alpha = std::min(1.0, options.max_move * width / speed);
    bool kept = false;
    double gain = 0;
    for (int h = 0; h <= kHalvings && !kept; ++h, alpha /= 2) {
      std::vector<Vector3d> trial = advected(device, x, field, alpha);
      Points tm = to_matrix(trial);
      if (domain.flipped(tm, faces).size() > flipped) {
        // slivers sheared past their width: repaired, when that costs no more area than a step's
        // discretisation does
        repair_flips(domain, faces, Eigen::VectorXd(), tm);  // the neighbour-mean repair (dense_surface.hpp)
        if (domain.flipped(tm, faces).size() > flipped ||
            surface_metrics(to_matrix(x), tm, faces, SurfaceDomain::sphere).face_area_ratio.mean_abs_dev > kRepairAreaChange)
          continue;
        trial = unit_rows(tm);
      }
      std::vector<int> th = hint;
      Eigen::VectorXd te;
      std::vector<Vector3d> tg;
      sample(tl, trial, f, th, te, &tg);
      const double Et = mismatch(te, area);
      if (!(Et < E * (1 - kMinGain))) continue;
      kept = true;
      gain = (E - Et) / E;
      x = std::move(trial);
      carried = advected(device, carried, field, alpha);
      hint = std::move(th), e = std::move(te), grad = std::move(tg), E = Et;
    }
    if (!kept) break;
    ++lv.iterations;
    if (gain < kLevelGain) break;
  }
  lv.mismatch_after = E;
  return lv;
}

// The rotation search (sphere_rotation.hpp) with both scalars smoothed at `width`; x rotated
// when the rotation found halves 1 - correlation.
void rotate_first(std::vector<Vector3d>& x, const Points& reference, const Triangles& faces, const Eigen::VectorXd& values,
                  const SphereTemplate& templ, const SphereLocator& locator, const Eigen::VectorXd& area,
                  const Eigen::VectorXd& tarea, double width, SphereMatchReport& rep) {
  const Eigen::VectorXd f = standardise(smooth(reference, values, area, width), area, "subject");
  const Eigen::VectorXd g = standardise(smooth(templ.sphere, templ.values, tarea, width), tarea, "template");
  const RotationFound found = search_rotation(to_matrix(x), faces, f, locator, g);
  rep.rotation_searched = true;
  rep.search_correlation_identity = found.correlation_identity;
  rep.search_correlation_best = found.correlation;
  if (!(1 - found.correlation <= kRotationGain * (1 - found.correlation_identity))) return;
  rep.rotation = found.rotation;
  for (Vector3d& p : x) p = (found.rotation * p).normalized();
}

}  // namespace

SphereMatchReport match_on_sphere(Device& device, std::vector<Vector3d>& x, std::vector<Vector3d>& carried, const Points& reference,
                                  const Triangles& faces, const Eigen::VectorXd& values, const SphereTemplate& templ,
                                  const SphereMatchOptions& options, const SurfaceDomainMoves& domain) {
  const auto t0 = Clock::now();
  SphereMatchReport rep;
  const Eigen::VectorXd area = vertex_areas(reference, faces), tarea = vertex_areas(templ.sphere, templ.faces);
  const SphereLocator locator(templ.sphere, templ.faces);
  std::vector<int> hint(x.size(), -1);
  const Eigen::VectorXd f0 = standardise(values, area, "subject"), g0 = standardise(templ.values, tarea, "template");
  TemplateLevel raw{&locator, g0, {}};
  raw.grad.assign(static_cast<size_t>(g0.size()), Vector3d::Zero());
  Eigen::VectorXd e;
  sample(raw, x, f0, hint, e, nullptr);
  rep.correlation_before = correlation(f0, f0 + e, area);
  if (carried.empty() && options.rotation_search && options.iterations > 0 && !options.widths.empty())
    rotate_first(x, reference, faces, values, templ, locator, area, tarea, options.widths.front(), rep);
  for (double width : dense_widths(options.widths, to_matrix(carried), reference, faces)) {
    if (options.iterations <= 0) break;
    rep.levels.push_back(match_level(device, x, carried, reference, faces, values, templ, locator, area, tarea, width, options, domain, hint));
  }
  sample(raw, x, f0, hint, e, nullptr);
  rep.correlation_after = correlation(f0, f0 + e, area);
  rep.seconds = seconds_since(t0);
  return rep;
}

}  // namespace vpm::detail
