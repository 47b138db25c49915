// The dense iterations of a registration in the unit disk (disk_match.hpp): smoothed,
// standardised scalars on a square grid, Gauss-Newton steps of the disk's stream-function field
// with its centres on a triangular lattice, coarse to fine.
#include "register/disk_match.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "map/surface_area.hpp"
#include "register/dense_surface.hpp"
#include "register/disk_field.hpp"
#include "register/point_bins.hpp"
#include "vpm/error.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

// The lattice of the field's centres: spacing 0.94 x the level's width (the sphere's icosphere
// edges are 0.94 of its widths), at least kMinSpacing (about 36,000 centres), each centre a
// quarter spacing inside the circle at least (nearer, its stream function vanishes with
// 1 - |y|^2: columns that neither the data nor the smoothness hold).
constexpr double kSpacingPerWidth = 0.94, kMinSpacing = 0.01;
// The smoothing grid: node spacing sigma / 2, at most about kMaxNodes a side.
constexpr int kMaxNodes = 1024;
// Terms of the Gauss-Newton system with lambda |x - c|^2 beyond kSystemCutoff (below 1e-5 of the
// peak) are left out, and the Gram's beyond kGramCutoff (1e-10); the field itself uses every
// centre within kDiskCutoff.
constexpr double kSystemCutoff = 16, kGramCutoff = 25;

Eigen::Vector3d lifted(const Vector2d& p) { return Eigen::Vector3d(p.x(), p.y(), 0); }

// A scalar smoothed at scale sigma on a square grid of nodes (lo + i h, lo + j h), i, j < n,
// covering the disk with two nodes to spare, and its central-difference gradient; values and
// gradients between the nodes bilinear.
struct ScalarGrid {
  double lo = 0, h = 1;
  int n = 2;
  Eigen::VectorXd v;        // node (i, j) at j * n + i
  std::vector<Vector2d> d;  // the gradient at the nodes

  double at(const Vector2d& p, Vector2d* grad = nullptr) const {
    const double fx = std::clamp((p.x() - lo) / h, 0.0, n - 1.0), fy = std::clamp((p.y() - lo) / h, 0.0, n - 1.0);
    const int i = std::min(static_cast<int>(fx), n - 2), j = std::min(static_cast<int>(fy), n - 2);
    const double tx = fx - i, ty = fy - j;
    const int k[4] = {j * n + i, j * n + i + 1, (j + 1) * n + i, (j + 1) * n + i + 1};
    const double w[4] = {(1 - tx) * (1 - ty), tx * (1 - ty), (1 - tx) * ty, tx * ty};
    double s = 0;
    Vector2d g = Vector2d::Zero();
    for (int q = 0; q < 4; ++q) s += w[q] * v(k[q]), g += w[q] * d[static_cast<size_t>(k[q])];
    if (grad) *grad = g;
    return s;
  }
  Eigen::VectorXd at_rows(const Points& x) const {
    Eigen::VectorXd out(x.rows());
    for (Eigen::Index i = 0; i < x.rows(); ++i) out(i) = at(Vector2d(x(i, 0), x(i, 1)));
    return out;
  }
};

// The vertices' values smoothed (gaussian_average, as on the sphere) at the grid's nodes.
ScalarGrid smooth(const Points& x, const Eigen::VectorXd& values, const Eigen::VectorXd& area, double sigma) {
  ScalarGrid g;
  g.h = std::max(sigma / 2, 2.0 / (kMaxNodes - 6));
  g.n = static_cast<int>(std::ceil(2 / g.h)) + 5;
  g.lo = -1 - 2 * g.h;
  const int n = g.n;
  g.v = gaussian_average(x, values, area, sigma, n * n, [&](int k) { return Eigen::Vector3d(g.lo + (k % n) * g.h, g.lo + (k / n) * g.h, 0); });
  g.d.assign(static_cast<size_t>(n) * n, Vector2d::Zero());
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const int i0 = std::max(i - 1, 0), i1 = std::min(i + 1, n - 1), j0 = std::max(j - 1, 0), j1 = std::min(j + 1, n - 1);
      g.d[static_cast<size_t>(j * n + i)] = Vector2d((g.v(j * n + i1) - g.v(j * n + i0)) / ((i1 - i0) * g.h),
                                                     (g.v(j1 * n + i) - g.v(j0 * n + i)) / ((j1 - j0) * g.h));
    }
  return g;
}

// The grid standardised as its values at the vertices `x` (area shares `area`) are.
void standardise_grid(ScalarGrid& g, const Points& x, const Eigen::VectorXd& area, const char* what) {
  const Spread s = spread(g.at_rows(x), area, what);
  g.v = (g.v.array() - s.mean) / s.sd;
  for (Vector2d& d : g.d) d /= s.sd;
}

// The field's centres: a triangular lattice inside the disk, and their bins.
struct Lattice {
  std::vector<Vector2d> c;
  double lambda = 1;
  Points at;
  PointBins system_bins, field_bins;
  Lattice(std::vector<Vector2d> centres, double width)
      : c(std::move(centres)), lambda(1 / (width * width)), at(disk_points(c)),
        system_bins(at, std::sqrt(kSystemCutoff) * width), field_bins(at, std::sqrt(kDiskCutoff) * width) {}
  int size() const { return static_cast<int>(c.size()); }
};

std::vector<Vector2d> lattice_points(double width) {
  const double s = std::max(kSpacingPerWidth * width, kMinSpacing), dy = s * std::sqrt(3.0) / 2;
  std::vector<Vector2d> c;
  const int rows = static_cast<int>(1 / dy) + 1, cols = static_cast<int>(1 / s) + 2;
  for (int k = -rows; k <= rows; ++k)
    for (int m = -cols; m <= cols; ++m) {
      const Vector2d p((m + ((k & 1) ? 0.5 : 0.0)) * s, k * dy);
      if (p.norm() <= 1 - s / 4) c.push_back(p);
    }
  return c;
}

// v(x) = J sum_j M(x, c_j) b_j over the centres within reach.
struct LatticeField {
  const Lattice* at = nullptr;
  std::vector<Vector2d> b;
  Vector2d operator()(const Vector2d& x) const {
    Vector2d w = Vector2d::Zero();
    at->field_bins.visit(lifted(x), [&](int j) {
      const Vector2d& cj = at->c[static_cast<size_t>(j)];
      if (at->lambda * (x - cj).squaredNorm() <= kDiskCutoff) w += stream_hessian(x, cj, at->lambda) * b[static_cast<size_t>(j)];
    });
    return quarter_turn() * w;
  }
};

// The rows of the Gauss-Newton system: one a vertex (grad g(x_i)^T J M(x_i, c_j) for b_j), two a
// landmark (J M(p, c_j): the field there, held at zero).
SparseRows system_rows(const std::vector<Vector2d>& x, const std::vector<Vector2d>& grad, const std::vector<Vector2d>& landmarks,
                       const Lattice& lat) {
  const int n = static_cast<int>(x.size()), L = static_cast<int>(landmarks.size()), T = host_threads();
  std::vector<std::vector<Eigen::Triplet<double>>> part(static_cast<size_t>(T));
  const Matrix2d J = quarter_turn();
  parallel_for(T, 2, [&](int b0, int b1) {
    for (int blk = b0; blk < b1; ++blk)
      for (int i = blk; i < n + L; i += T) {
        const bool vertex = i < n;
        const Vector2d& p = vertex ? x[static_cast<size_t>(i)] : landmarks[static_cast<size_t>(i - n)];
        const Matrix2d s = vertex ? Matrix2d((Matrix2d() << grad[static_cast<size_t>(i)].transpose() * J, 0, 0).finished()) : J;
        const int first = vertex ? i : n + 2 * (i - n), count = vertex ? 1 : 2;
        lat.system_bins.visit(lifted(p), [&](int j) {
          const Vector2d& cj = lat.c[static_cast<size_t>(j)];
          if (lat.lambda * (p - cj).squaredNorm() > kSystemCutoff) return;
          const Matrix2d v = s * stream_hessian(p, cj, lat.lambda);
          for (int k = 0; k < count; ++k) {
            part[static_cast<size_t>(blk)].emplace_back(first + k, 2 * j, v(k, 0));
            part[static_cast<size_t>(blk)].emplace_back(first + k, 2 * j + 1, v(k, 1));
          }
        });
      }
  });
  std::vector<Eigen::Triplet<double>> all;
  for (const auto& t : part) all.insert(all.end(), t.begin(), t.end());
  SparseRows rows(n + 2 * L, 2 * lat.size());
  rows.setFromTriplets(all.begin(), all.end());
  return rows;
}

// The centres' Gram matrix (blocks M(c_j, c_k): the stream function's smoothness), sparse.
Eigen::SparseMatrix<double> centre_gram(const Lattice& lat) {
  std::vector<Eigen::Triplet<double>> t;
  const PointBins bins(lat.at, std::sqrt(kGramCutoff / lat.lambda));
  for (int j = 0; j < lat.size(); ++j)
    bins.visit(lifted(lat.c[static_cast<size_t>(j)]), [&](int k) {
      const Vector2d &cj = lat.c[static_cast<size_t>(j)], &ck = lat.c[static_cast<size_t>(k)];
      if (lat.lambda * (cj - ck).squaredNorm() > kGramCutoff) return;
      const Matrix2d b = stream_hessian(cj, ck, lat.lambda);
      for (int p = 0; p < 2; ++p)
        for (int q = 0; q < 2; ++q) t.emplace_back(2 * j + p, 2 * k + q, b(p, q));
    });
  Eigen::SparseMatrix<double> K(2 * lat.size(), 2 * lat.size());
  K.setFromTriplets(t.begin(), t.end());
  return K;
}

// Points moved through alpha x the stationary field on `device` (advect_in_disk: two RK4 steps),
// then put back on the domain.
std::vector<Vector2d> advected(Device& device, std::vector<Vector2d> x, const LatticeField& field, double alpha,
                               const std::vector<char>& boundary) {
  if (!x.empty()) advect_in_disk(device, x, {disk_carrier(field.at->lambda, field.at->c, field.b, alpha)}, 2, boundary);
  return x;
}

double max_speed(const std::vector<Vector2d>& x, const LatticeField& field) {
  std::vector<double> speed(x.size());
  parallel_for(static_cast<int>(x.size()), 1024, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) speed[static_cast<size_t>(i)] = field(x[static_cast<size_t>(i)]).norm();
  });
  return speed.empty() ? 0 : *std::max_element(speed.begin(), speed.end());
}

// The residuals e_i = g(x_i) - f_i and the gradients of g at x_i.
void sample(const ScalarGrid& g, const std::vector<Vector2d>& x, const Eigen::VectorXd& f, Eigen::VectorXd& e,
            std::vector<Vector2d>& grad) {
  e.resize(static_cast<Eigen::Index>(x.size()));
  grad.resize(x.size());
  parallel_for(static_cast<int>(x.size()), 1024, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) e(i) = g.at(x[static_cast<size_t>(i)], &grad[static_cast<size_t>(i)]) - f(i);
  });
}

}  // namespace

namespace {

// What a level works with: the subject's scalar at its vertices and the template's grid, both
// smoothed at the level's scale and standardised, the vertices' area shares. The subject's scalar
// is smoothed where its vertices are when the level starts, in the template's frame, not on its
// input disk: a deformation that shears (area-preserving maps do) turns a round Gaussian of the
// input disk into an ellipse there, and the two smoothed scalars would then differ even at the
// ideal registration (on the development patch, the gap to the ideal's Dice after the landmarks
// 0.038 / 0.152 / 0.182 with the input disk's smoothing, 0.005 / 0.102 / 0.168 with this).
struct LevelScalars {
  Eigen::VectorXd f, area;
  ScalarGrid g;
};

// One level: at most options.iterations Gauss-Newton steps of a field of width `width`; a step
// that crushes faces at every halving gives the face areas back first (kReliefs, dense_surface.hpp);
// `area0`: the input disk's face areas.
SphereMatchLevel match_level(Device& device, std::vector<Vector2d>& x, std::vector<Vector2d>& carried, const Eigen::VectorXd& area0, const Triangles& faces, const LevelScalars& s,
                             double width, const SphereMatchOptions& options, const SurfaceDomainMoves& domain) {
  SphereMatchLevel lv;
  lv.width = width;
  const Lattice lat(lattice_points(width), width);
  lv.centres = lat.size();
  const Eigen::SparseMatrix<double> K = centre_gram(lat);
  Eigen::VectorXd e;
  std::vector<Vector2d> grad;
  sample(s.g, x, s.f, e, grad);
  double E = lv.mismatch_before = mismatch(e, s.area);
  const size_t flipped = domain.flipped(disk_points(x), faces).size();  // the step may not add any
  for (int it = 0; it < options.iterations; ++it) {
    const Eigen::VectorXd a = gauss_newton_weights(system_rows(x, grad, carried, lat), s.area, e, K, options.ridge, "disk registration");
    LatticeField field{&lat, {}};
    for (int j = 0; j < lat.size(); ++j) field.b.push_back(a.segment<2>(2 * j));
    const double speed = max_speed(x, field);
    if (!(speed > 0)) break;
    double alpha = std::min(1.0, options.max_move * width / speed), gain = 0;
    bool kept = false, crushed = false;
    const double least = smallest_area_ratio(area0, disk_points(x), faces);  // x stays through the halvings
    for (int h = 0; h <= kHalvings && !kept; ++h, alpha /= 2) {
      std::vector<Vector2d> trial = advected(device, x, field, alpha, domain.boundary);
      Points tm = disk_points(trial);
      if (crushes(area0, least, tm, faces)) {
        crushed = true;
        continue;
      }
      if (domain.flipped(tm, faces).size() > flipped) {  // repaired when that costs little area
        repair_flips(domain, faces, Eigen::VectorXd(), tm);  // the neighbour-mean repair (dense_surface.hpp)
        if (domain.flipped(tm, faces).size() > flipped ||
            surface_metrics(disk_points(x), tm, faces, SurfaceDomain::disk).face_area_ratio.mean_abs_dev > kRepairAreaChange) {
          crushed = true;
          continue;
        }
        trial = disk_vectors(tm);
      }
      Eigen::VectorXd te;
      std::vector<Vector2d> tg;
      sample(s.g, trial, s.f, te, tg);
      const double Et = mismatch(te, s.area);
      if (!(Et < E * (1 - kMinGain))) continue;
      kept = true;
      gain = (E - Et) / E;
      x = std::move(trial);
      carried = advected(device, carried, field, alpha, {});
      e = std::move(te), grad = std::move(tg), E = Et;
    }
    if (!kept && crushed && lv.reliefs < kReliefs) {  // faces crushed: their areas back, then on
      Points tm = disk_points(x);
      if (relieve_areas(domain, area0, faces, kReliefRounds, tm)) {
        ++lv.reliefs;
        x = disk_vectors(tm);
        sample(s.g, x, s.f, e, grad);
        E = mismatch(e, s.area);
        continue;
      }
    }
    if (!kept) break;
    ++lv.iterations;
    if (gain < kLevelGain) break;
  }
  lv.mismatch_after = E;
  return lv;
}

LevelScalars level_scalars(const Points& at, const Eigen::VectorXd& values, const Eigen::VectorXd& area, const DiskTemplate& templ,
                           const Eigen::VectorXd& tarea, double sigma) {
  LevelScalars s{standardise(smooth(at, values, area, sigma).at_rows(at), area, "subject"), area,
                 smooth(templ.disk, templ.values, tarea, sigma)};
  standardise_grid(s.g, templ.disk, tarea, "template");
  return s;
}

// Without landmarks: the rotation about the centre that best correlates the scalars smoothed at
// `width` (every 5 degrees, then a pattern search down to 0.01 degree), applied when it shrinks
// 1 - correlation to kRotationGain of what it was; not searched when they correlate kAligned.
void rotate_first(std::vector<Vector2d>& x, const LevelScalars& s, SphereMatchReport& rep) {
  auto corr = [&](double angle) {
    const Eigen::Rotation2Dd R(angle);
    Eigen::VectorXd g(static_cast<Eigen::Index>(x.size()));
    for (size_t i = 0; i < x.size(); ++i) g(static_cast<Eigen::Index>(i)) = s.g.at(R * x[i]);
    return correlation(g, s.f, s.area);
  };
  rep.search_correlation_identity = rep.search_correlation_best = corr(0);
  if (rep.search_correlation_identity >= kAligned) return;
  rep.rotation_searched = true;
  double best = 0, c = rep.search_correlation_identity;
  for (int k = 1; k < 72; ++k)
    if (const double ck = corr(k * M_PI / 36); ck > c) c = ck, best = k * M_PI / 36;
  for (double step = M_PI / 72; step > 1e-4; step /= 2)
    for (double t : {best - step, best + step})
      if (const double ct = corr(t); ct > c) c = ct, best = t;
  rep.search_correlation_best = c;
  if (!(1 - c <= kRotationGain * (1 - rep.search_correlation_identity))) return;
  rep.rotation = Eigen::AngleAxisd(best, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Rotation2Dd R(best);
  for (Vector2d& p : x) p = R * p;
}

// The template's unsmoothed scalar at the points x, linear on its faces: located on the template
// lifted onto the upper hemisphere by Lambert's equal-area projection (the unit disk's circle on
// the equator), where vpm::SphereLocator finds the face whose cone holds each point.
Eigen::VectorXd template_at(const DiskTemplate& templ, const std::vector<Vector2d>& x) {
  auto up = [](const Vector2d& p) {
    const double r2 = std::min(p.squaredNorm(), 1.0), s = std::sqrt(2 - r2);
    return Eigen::Vector3d(s * p.x(), s * p.y(), 1 - r2 + 1e-12);
  };
  Points sphere(templ.disk.rows(), 3), at(static_cast<Eigen::Index>(x.size()), 3);
  for (Eigen::Index i = 0; i < templ.disk.rows(); ++i) sphere.row(i) = up(Vector2d(templ.disk(i, 0), templ.disk(i, 1))).normalized().transpose();
  for (size_t i = 0; i < x.size(); ++i) at.row(static_cast<Eigen::Index>(i)) = up(x[i]).transpose();
  const SphereLocator locator(sphere, templ.faces);
  const std::vector<SphereLocation> loc = locator.locate_all(at);
  Eigen::VectorXd out(static_cast<Eigen::Index>(x.size()));
  for (size_t i = 0; i < x.size(); ++i) {
    out(static_cast<Eigen::Index>(i)) = 0;
    for (int k = 0; k < 3; ++k) out(static_cast<Eigen::Index>(i)) += loc[i].bary[k] * templ.values(templ.faces(loc[i].face, k));
  }
  return out;
}

}  // namespace

SphereMatchReport match_in_disk(Device& device, std::vector<Vector2d>& x, std::vector<Vector2d>& carried, const Points& reference, const Triangles& faces,
                                const Eigen::VectorXd& values, const DiskTemplate& templ, const SphereMatchOptions& options,
                                const SurfaceDomainMoves& domain) {
  const auto t0 = Clock::now();
  SphereMatchReport rep;
  const Eigen::VectorXd area = vertex_areas(reference, faces), tarea = vertex_areas(templ.disk, templ.faces);
  const Eigen::VectorXd area0 = face_areas(reference, faces);
  const Eigen::VectorXd f0 = standardise(values, area, "subject");
  spread(templ.values, tarea, "template");  // refuses a constant template
  rep.correlation_before = correlation(f0, template_at(templ, x), area);
  if (carried.empty() && options.rotation_search && options.iterations > 0 && !options.widths.empty())
    rotate_first(x, level_scalars(disk_points(x), values, area, templ, tarea, options.widths.front()), rep);
  for (double width : dense_widths(options.widths, disk_points(carried), reference, faces)) {
    if (options.iterations <= 0) break;
    const LevelScalars s = level_scalars(disk_points(x), values, area, templ, tarea, options.smoothing * width);
    rep.levels.push_back(match_level(device, x, carried, area0, faces, s, width, options, domain));
  }
  rep.correlation_after = correlation(f0, template_at(templ, x), area);
  rep.seconds = seconds_since(t0);
  return rep;
}

}  // namespace vpm::detail
