// The dense iterations of a registration on the sphere (sphere_match.hpp): smoothed, standardised
// scalars, the template's located at the subject's vertices, Gauss-Newton steps of a
// surface-divergence-free Gaussian field with its centres on an icosphere, coarse to fine.
#include "register/sphere_match.hpp"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "map/surface_area.hpp"
#include "register/point_bins.hpp"
#include "register/sphere_field.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

// Terms of the Gauss-Newton system with lambda |x - c|^2 beyond this are left out (below 1e-5
// of the peak; the step's direction only: the field itself uses every centre within
// kSphereCutoff).
constexpr double kSystemCutoff = 16;
// A step is kept when it lowers the mismatch by this fraction at least; a level ends when the
// gain is below kLevelGain.
constexpr double kMinGain = 1e-4, kLevelGain = 1e-3;
constexpr int kHalvings = 4;
// A step whose flipped slivers were repaired is kept only if the repaired step changes the face
// areas (mean |r - 1| against the positions before it) by at most this.
constexpr double kRepairAreaChange = 0.001;
// How firmly the dense steps hold the landmarks (hold_landmarks).
constexpr double kHold = 10;

std::vector<Vector3d> rows(const Points& m) {
  std::vector<Vector3d> v(static_cast<size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) v[static_cast<size_t>(i)] = m.row(i).transpose().normalized();
  return v;
}

Points matrix(const std::vector<Vector3d>& v) {
  Points m(static_cast<Eigen::Index>(v.size()), 3);
  for (size_t i = 0; i < v.size(); ++i) m.row(static_cast<Eigen::Index>(i)) = v[i].transpose();
  return m;
}

// A third of the chord areas of each vertex's faces.
Eigen::VectorXd vertex_areas(const Points& x, const Triangles& f) {
  const Eigen::VectorXd a = face_areas(x, f);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(x.rows());
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) v(f(t, k)) += a(t) / 3;
  return v;
}

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
Eigen::VectorXd smooth(const Points& x, const Triangles& f, const Eigen::VectorXd& values, const Eigen::VectorXd& area,
                       double sigma) {
  const TriSurface nodes = icosphere(centre_level(sigma / 2));
  const Eigen::Index m = nodes.vertices.rows();
  const double radius = 3 * sigma, inv = 1 / (2 * sigma * sigma);
  const PointBins bins(x, radius);
  Eigen::VectorXd at(m);
  parallel_for(static_cast<int>(m), 64, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      const Vector3d p = nodes.vertices.row(i).transpose();
      double num = 0, den = 0;
      bins.visit(p, [&](int j) {
        const double d2 = (x.row(j).transpose() - p).squaredNorm();
        if (d2 > radius * radius) return;
        const double w = area(j) * std::exp(-d2 * inv);
        num += w * values(j);
        den += w;
      });
      at(i) = den > 0 ? num / den : 0;
    }
  });
  (void)f;
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

// Area-weighted standardisation: mean 0, spread 1 (InputError naming `what` for a constant scalar).
Eigen::VectorXd standardise(const Eigen::VectorXd& v, const Eigen::VectorXd& area, const char* what) {
  const double total = area.sum(), mean = area.dot(v) / total;
  const Eigen::VectorXd c = v.array() - mean;
  const double sd = std::sqrt(area.dot(c.cwiseProduct(c)) / total);
  if (!(sd > 1e-12 * (1 + std::abs(mean)))) throw InputError(std::string(what) + ": the scalar is constant; nothing to match");
  return c / sd;
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

double mismatch(const Eigen::VectorXd& e, const Eigen::VectorXd& area) { return area.dot(e.cwiseProduct(e)) / area.sum(); }

// The centres' Gram matrix K (2C x 2C, blocks P_j^T H_jk P_k) and bases P_j.
Eigen::MatrixXd centre_gram(const std::vector<Vector3d>& c, const std::vector<Eigen::Matrix<double, 3, 2>>& P, double lambda) {
  const int C = static_cast<int>(c.size());
  Eigen::MatrixXd K(2 * C, 2 * C);
  for (int j = 0; j < C; ++j)
    for (int k = 0; k < C; ++k) K.block<2, 2>(2 * j, 2 * k) = P[j].transpose() * gaussian_hessian(c[j] - c[k], lambda) * P[k];
  return K;
}

// The Gauss-Newton system sum_i a_i J_i^T J_i, -sum_i a_i J_i^T e_i with J_i's block at centre j
// (grad_i x x_i)^T H(x_i, c_j) P_j (the change of e_i per weight a_j).
void normal_equations(const std::vector<Vector3d>& x, const std::vector<Vector3d>& grad, const Eigen::VectorXd& e,
                      const Eigen::VectorXd& area, const std::vector<Vector3d>& c,
                      const std::vector<Eigen::Matrix<double, 3, 2>>& P, double lambda, Eigen::MatrixXd& N, Eigen::VectorXd& b) {
  const int C = static_cast<int>(c.size()), n = static_cast<int>(x.size()), T = host_threads();
  std::vector<Eigen::MatrixXd> Ns(static_cast<size_t>(T), Eigen::MatrixXd::Zero(2 * C, 2 * C));
  std::vector<Eigen::VectorXd> bs(static_cast<size_t>(T), Eigen::VectorXd::Zero(2 * C));
  parallel_for(T, 2, [&](int b0, int b1) {
    for (int blk = b0; blk < b1; ++blk) {
      Eigen::MatrixXd& Nt = Ns[static_cast<size_t>(blk)];
      Eigen::VectorXd& bt = bs[static_cast<size_t>(blk)];
      std::vector<int> idx;
      Eigen::VectorXd row(2 * C);
      for (int i = blk; i < n; i += T) {
        const Vector3d s = grad[static_cast<size_t>(i)].cross(x[static_cast<size_t>(i)]);
        if (s.squaredNorm() == 0) continue;
        idx.clear();
        int m = 0;
        for (int j = 0; j < C; ++j) {
          const Vector3d r = x[static_cast<size_t>(i)] - c[static_cast<size_t>(j)];
          if (lambda * r.squaredNorm() > kSystemCutoff) continue;
          row.segment<2>(m) = (s.transpose() * gaussian_hessian(r, lambda) * P[static_cast<size_t>(j)]).transpose();
          idx.push_back(j);
          m += 2;
        }
        const double a = area(i);
        for (size_t p = 0; p < idx.size(); ++p) {
          bt.segment<2>(2 * idx[p]) -= a * e(i) * row.segment<2>(2 * static_cast<int>(p));
          for (size_t q = p; q < idx.size(); ++q)
            Nt.block<2, 2>(2 * idx[p], 2 * idx[q]) += a * row.segment<2>(2 * static_cast<int>(p)) * row.segment<2>(2 * static_cast<int>(q)).transpose();
        }
      }
    }
  });
  N = Eigen::MatrixXd::Zero(2 * C, 2 * C);
  b = Eigen::VectorXd::Zero(2 * C);
  for (int t = 0; t < T; ++t) N += Ns[static_cast<size_t>(t)], b += bs[static_cast<size_t>(t)];
  // the blocks were added for centre pairs j <= k only (in the order the vertex met them, which is
  // increasing j): mirror the upper triangle
  N.triangularView<Eigen::StrictlyLower>() = N.transpose().triangularView<Eigen::StrictlyLower>();
}

}  // namespace

namespace {


// Area-weighted correlation of two scalars.
double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& w) {
  const double W = w.sum();
  const Eigen::VectorXd ca = a.array() - w.dot(a) / W, cb = b.array() - w.dot(b) / W;
  const double d = std::sqrt(w.dot(ca.cwiseProduct(ca)) * w.dot(cb.cwiseProduct(cb)));
  return d > 0 ? w.dot(ca.cwiseProduct(cb)) / d : 0;
}

// The landmarks held: sum_p M_p^T M_p, M_p (2 x 2C) the field's tangent components at the
// landmark p per weight (B_p^T [p]x H(p, c_j) P_j), scaled to kHold x the data term's trace, so
// the step's field nearly vanishes at the landmarks and the dense steps keep what they matched.
void hold_landmarks(const std::vector<Vector3d>& carried, const std::vector<Vector3d>& c,
                    const std::vector<Eigen::Matrix<double, 3, 2>>& P, double lambda, Eigen::MatrixXd& N) {
  if (carried.empty()) return;
  const int C = static_cast<int>(c.size());
  Eigen::MatrixXd hold = Eigen::MatrixXd::Zero(2 * C, 2 * C);
  Eigen::MatrixXd M(2, 2 * C);
  for (const Vector3d& p : carried) {
    const Eigen::Matrix<double, 3, 2> B = tangent_basis(p);
    Eigen::Matrix3d cross;
    cross << 0, -p.z(), p.y(), p.z(), 0, -p.x(), -p.y(), p.x(), 0;
    for (int j = 0; j < C; ++j)
      M.block<2, 2>(0, 2 * j) = B.transpose() * cross * gaussian_hessian(p - c[static_cast<size_t>(j)], lambda) * P[static_cast<size_t>(j)];
    hold.noalias() += M.transpose() * M;
  }
  if (hold.trace() > 0) N += kHold * N.trace() / hold.trace() * hold;
}

// The field of the Gauss-Newton step at one level: weights u_j = P_j a_j, a the solution of
// (N + mu K) a = b, mu = ridge x tr(N) / tr(K).
SphereField gauss_newton_field(Eigen::MatrixXd N, const Eigen::VectorXd& b, const Eigen::MatrixXd& K,
                               const std::vector<Vector3d>& c, const std::vector<Eigen::Matrix<double, 3, 2>>& P,
                               double lambda, double ridge) {
  const double mu = ridge * N.trace() / K.trace();
  N += mu * K;
  N.diagonal().array() += 1e-12 * N.diagonal().maxCoeff();
  const Eigen::LLT<Eigen::MatrixXd> llt(N);
  if (llt.info() != Eigen::Success) throw NumericalError("sphere registration: the dense step's system is not positive definite");
  const Eigen::VectorXd a = llt.solve(b);
  SphereField field;
  field.lambda = lambda;
  field.centres = c;
  field.weights.resize(c.size());
  for (size_t j = 0; j < c.size(); ++j) field.weights[j] = P[j] * a.segment<2>(2 * static_cast<Eigen::Index>(j));
  return field;
}

// Points moved through `alpha` x the stationary field (two RK4 steps).
std::vector<Vector3d> advected(std::vector<Vector3d> x, SphereField field, double alpha) {
  for (Vector3d& w : field.weights) w *= alpha;
  rk4_step(x, field, field, field, 0.5);
  rk4_step(x, field, field, field, 0.5);
  return x;
}

double max_speed(const std::vector<Vector3d>& x, const SphereField& field) {
  std::vector<double> part(static_cast<size_t>(host_threads()), 0.0);
  const int T = host_threads(), n = static_cast<int>(x.size());
  parallel_for(T, 2, [&](int b0, int b1) {
    for (int blk = b0; blk < b1; ++blk)
      for (int i = blk; i < n; i += T) part[static_cast<size_t>(blk)] = std::max(part[static_cast<size_t>(blk)], field(x[static_cast<size_t>(i)]).norm());
  });
  return *std::max_element(part.begin(), part.end());
}

// One level: the scalars smoothed at smoothing x width, the centres on an icosphere, at most
// options.iterations Gauss-Newton steps.
SphereMatchLevel match_level(std::vector<Vector3d>& x, std::vector<Vector3d>& carried, const Points& reference,
                             const Triangles& faces, const Eigen::VectorXd& values, const SphereTemplate& templ,
                             const SphereLocator& locator, const Eigen::VectorXd& area, const Eigen::VectorXd& tarea,
                             double width, const SphereMatchOptions& options, const SurfaceDomainMoves& domain,
                             std::vector<int>& hint) {
  SphereMatchLevel lv;
  lv.width = width;
  const double sigma = options.smoothing * width, lambda = 1 / (width * width);
  const Eigen::VectorXd f = standardise(smooth(reference, faces, values, area, sigma), area, "subject");
  TemplateLevel tl{&locator, standardise(smooth(templ.sphere, templ.faces, templ.values, tarea, sigma), tarea, "template"), {}};
  tl.grad = vertex_gradients(templ.sphere, templ.faces, tl.g);
  const std::vector<Vector3d> c = rows(icosphere(centre_level(width)).vertices);
  std::vector<Eigen::Matrix<double, 3, 2>> P(c.size());
  for (size_t j = 0; j < c.size(); ++j) P[j] = weight_basis(c[j]);
  lv.centres = static_cast<int>(c.size());
  const Eigen::MatrixXd K = centre_gram(c, P, lambda);
  Eigen::VectorXd e;
  std::vector<Vector3d> grad;
  sample(tl, x, f, hint, e, &grad);
  double E = lv.mismatch_before = mismatch(e, area);
  const size_t flipped = domain.flipped(matrix(x), faces).size();  // the step may not add any
  for (int it = 0; it < options.iterations; ++it) {
    Eigen::MatrixXd N;
    Eigen::VectorXd b;
    normal_equations(x, grad, e, area, c, P, lambda, N, b);
    hold_landmarks(carried, c, P, lambda, N);
    const SphereField field = gauss_newton_field(std::move(N), b, K, c, P, lambda, options.ridge);
    const double speed = max_speed(x, field);
    if (!(speed > 0)) break;
    double alpha = std::min(1.0, options.max_move * width / speed);
    bool kept = false;
    double gain = 0;
    for (int h = 0; h <= kHalvings && !kept; ++h, alpha /= 2) {
      std::vector<Vector3d> trial = advected(x, field, alpha);
      Points tm = matrix(trial);
      if (domain.flipped(tm, faces).size() > flipped) {
        // slivers sheared past their width: repaired, when that costs no more area than a step's
        // discretisation does
        repair_sphere_flips(domain, faces, tm);
        if (domain.flipped(tm, faces).size() > flipped ||
            surface_metrics(matrix(x), tm, faces, SurfaceDomain::sphere).face_area_ratio.mean_abs_dev > kRepairAreaChange)
          continue;
        trial = rows(tm);
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
      carried = advected(carried, field, alpha);
      hint = std::move(th), e = std::move(te), grad = std::move(tg), E = Et;
    }
    if (!kept) break;
    ++lv.iterations;
    if (gain < kLevelGain) break;
  }
  lv.mismatch_after = E;
  return lv;
}

// The levels that run: with landmarks, those narrower than the landmarks' mean nearest-neighbour
// chord (the landmark flow has set the deformation on the scales above it; a wider dense level
// there pulls against the held landmarks), at least the finest.
std::vector<double> dense_widths(const std::vector<double>& widths, const std::vector<Vector3d>& landmarks) {
  if (landmarks.size() < 2 || widths.empty()) return widths;
  double spacing = 0;
  for (size_t i = 0; i < landmarks.size(); ++i) {
    double best = 2;
    for (size_t j = 0; j < landmarks.size(); ++j)
      if (j != i) best = std::min(best, (landmarks[i] - landmarks[j]).norm());
    spacing += best / static_cast<double>(landmarks.size());
  }
  std::vector<double> out;
  for (double w : widths)
    if (w < spacing) out.push_back(w);
  if (out.empty()) out.push_back(*std::min_element(widths.begin(), widths.end()));
  return out;
}

}  // namespace

SphereMatchReport match_on_sphere(std::vector<Vector3d>& x, std::vector<Vector3d>& carried, const Points& reference,
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
  for (double width : dense_widths(options.widths, carried)) {
    if (options.iterations <= 0) break;
    rep.levels.push_back(match_level(x, carried, reference, faces, values, templ, locator, area, tarea, width, options, domain, hint));
  }
  sample(raw, x, f0, hint, e, nullptr);
  rep.correlation_after = correlation(f0, f0 + e, area);
  rep.seconds = seconds_since(t0);
  return rep;
}

}  // namespace vpm::detail
