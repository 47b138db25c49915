// What the dense registrations on the sphere and in the disk share (dense_surface.hpp).
#include "register/dense_surface.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/parallel.hpp"
#include "linalg/sparse_cholesky.hpp"
#include "map/surface_area.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

// How firmly the dense steps hold the landmarks (gauss_newton_weights). At 10 the landmarks
// drifted and the landmark flow that puts them back undid the dense steps' work (one report run
// on the sphere ended 0.0148 rad from the truth, farther than the landmarks alone); 100, chosen on
// the development set (the gap narrowed on two of three seeds), brings every report run within
// 0.01 of the ideal Dice (docs/surfaces.md "Measured").
constexpr double kHold = 100;

// J^T diag(w) J, the rows of J in one block per host thread (Eigen's sparse product is serial;
// it was a quarter of a 64k-face registration).
Eigen::SparseMatrix<double> normal_matrix(const SparseRows& J, const Eigen::VectorXd& w) {
  const int T = std::max(1, std::min(host_threads(), static_cast<int>(J.rows() / 4096)));
  std::vector<Eigen::SparseMatrix<double>> part(static_cast<size_t>(T));
  parallel_for(T, 1, [&](int b0, int b1) {
    for (int b = b0; b < b1; ++b) {
      const Eigen::Index r0 = J.rows() * b / T, r1 = J.rows() * (b + 1) / T;
      const Eigen::SparseMatrix<double> Jb = J.middleRows(r0, r1 - r0);
      const Eigen::SparseMatrix<double> WJb = w.segment(r0, r1 - r0).asDiagonal() * Jb;
      part[static_cast<size_t>(b)] = Eigen::SparseMatrix<double>(Jb.transpose()) * WJb;
    }
  });
  for (size_t b = 1; b < part.size(); ++b) part[0] += part[b];
  return part[0];
}

}  // namespace

Eigen::VectorXd vertex_areas(const Points& x, const Triangles& f) {
  const Eigen::VectorXd a = face_areas(x, f);
  Eigen::VectorXd v = Eigen::VectorXd::Zero(x.rows());
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) v(f(t, k)) += a(t) / 3;
  return v;
}

Spread spread(const Eigen::VectorXd& v, const Eigen::VectorXd& area, const char* what) {
  const double total = area.sum(), mean = area.dot(v) / total;
  const Eigen::VectorXd c = v.array() - mean;
  const double sd = std::sqrt(area.dot(c.cwiseProduct(c)) / total);
  if (!(sd > 1e-12 * (1 + std::abs(mean)))) throw InputError(std::string(what) + ": the scalar is constant; nothing to match");
  return {mean, sd};
}

Eigen::VectorXd standardise(const Eigen::VectorXd& v, const Eigen::VectorXd& area, const char* what) {
  const Spread s = spread(v, area, what);
  return (v.array() - s.mean) / s.sd;
}

double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& w) {
  const double W = w.sum();
  const Eigen::VectorXd ca = a.array() - w.dot(a) / W, cb = b.array() - w.dot(b) / W;
  const double d = std::sqrt(w.dot(ca.cwiseProduct(ca)) * w.dot(cb.cwiseProduct(cb)));
  return d > 0 ? w.dot(ca.cwiseProduct(cb)) / d : 0;
}

// A level narrower than this many times the subject's mean edge (the side of an equilateral
// triangle of the mean face area) is left out: its Gaussians are sampled by a handful of vertices
// each, as many unknowns as equations, at the cost of the finest system (on 2,562 vertices the
// 0.07 level took 10 of 12 s). Every surface of the development and report sets (19k-128k faces)
// runs every default level.
constexpr double kWidthPerEdge = 1.5;

// The levels that run: with landmarks, those narrower than the landmarks' mean nearest-neighbour
// chord (the landmark flow has set the deformation on the scales above it; a wider dense level
// there pulls against the held landmarks), at least the finest; of those, the ones at least
// kWidthPerEdge mean edges wide (at least the widest).
std::vector<double> dense_widths(const std::vector<double>& widths, const Points& landmarks, const Points& reference,
                                 const Triangles& faces) {
  std::vector<double> out = widths;
  const Eigen::Index L = landmarks.rows();
  if (L >= 2 && !widths.empty()) {
    double spacing = 0;
    for (Eigen::Index i = 0; i < L; ++i) {
      double best = 2;
      for (Eigen::Index j = 0; j < L; ++j)
        if (j != i) best = std::min(best, (landmarks.row(i) - landmarks.row(j)).norm());
      spacing += best / static_cast<double>(L);
    }
    out.clear();
    for (double w : widths)
      if (w < spacing) out.push_back(w);
    if (out.empty()) out.push_back(*std::min_element(widths.begin(), widths.end()));
  }
  const double edge = std::sqrt(4 / std::sqrt(3.0) * face_areas(reference, faces).mean());
  std::vector<double> resolved;
  for (double w : out)
    if (w >= kWidthPerEdge * edge) resolved.push_back(w);
  if (resolved.empty() && !out.empty()) resolved.push_back(*std::max_element(out.begin(), out.end()));
  return resolved;
}

void check_match_options(const SphereMatchOptions& o, const char* who) {
  const std::string w(who);
  for (double width : o.widths)
    if (!(width > 0 && width <= 2)) throw InputError(w + ": dense widths must be in (0, 2] (chord lengths), got " + std::to_string(width));
  if (!(o.smoothing > 0 && std::isfinite(o.smoothing))) throw InputError(w + ": the dense smoothing must be positive");
  if (!(o.max_move > 0 && o.max_move <= 1)) throw InputError(w + ": the dense max_move must be in (0, 1]");
  if (!(o.ridge >= 0 && std::isfinite(o.ridge))) throw InputError(w + ": the dense ridge must be non-negative");
  if (o.iterations < 0) throw InputError(w + ": dense iterations must be non-negative");
}

// The normal equations (sparse: centres interact within a few widths) by a sparse Cholesky
// factorisation (CHOLMOD's supernodal one where vpm has it: linalg/sparse_cholesky.hpp).
Eigen::VectorXd gauss_newton_weights(const SparseRows& J, const Eigen::VectorXd& area, const Eigen::VectorXd& e,
                                     const Eigen::SparseMatrix<double>& K, double ridge, const char* who) {
  const Eigen::Index n = area.size(), m = J.rows();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(m), r = Eigen::VectorXd::Zero(m);
  w.head(n) = area;
  r.head(n) = e;
  const Eigen::VectorXd sq = J.cwiseProduct(J) * Eigen::VectorXd::Ones(J.cols());  // |J_i|^2
  const double data = area.dot(sq.head(n)), held = sq.tail(m - n).sum();
  if (m > n && held > 0) w.tail(m - n).setConstant(kHold * data / held);
  const double mu = ridge * data / K.diagonal().sum();
  Eigen::SparseMatrix<double> N = normal_matrix(J, w);
  N += mu * K;
  SparseCholesky chol;
  if (!chol.factorize(N)) throw NumericalError(std::string(who) + ": the dense step's system could not be factored");
  return chol.solve(Eigen::VectorXd(-(J.transpose() * w.cwiseProduct(r))));
}

void restore_areas(const SurfaceDomainMoves& domain, const Points& reference, const Triangles& faces,
                   const SurfaceRegistrationOptions& options, SurfaceRegistrationResult& res) {
  if (options.restore_rounds <= 0 || !domain.flipped(res.points, faces).empty() ||
      surface_metrics(reference, res.points, faces, domain.domain).face_area_ratio.mean_abs_dev <= options.restore_tolerance)
    return;
  SurfaceMapOptions polish;
  polish.tolerance = options.restore_tolerance;
  polish.polish_rounds = options.restore_rounds;
  SurfaceMapReport rep;
  polish_surface(domain, faces, face_areas(reference, faces), polish, res.points, rep);
  res.restore_rounds = static_cast<int>(rep.polish.size());
  for (char c : domain.fixed) res.held_vertices += c;
}

double smallest_area_ratio(const Eigen::VectorXd& area0, const Points& x, const Triangles& faces) {
  return (face_areas(x, faces).array() / area0.array()).minCoeff();
}

bool crushes(const Eigen::VectorXd& area0, double least, const Points& after, const Triangles& faces) {
  const double now = smallest_area_ratio(area0, after, faces);
  return now < kCrushedArea && now < least;
}

bool relieve_areas(const SurfaceDomainMoves& domain, const Eigen::VectorXd& area0, const Triangles& faces, int rounds, Points& x) {
  if (rounds <= 0 || !domain.flipped(x, faces).empty()) return false;
  SurfaceMapOptions polish;
  polish.tolerance = 0;
  polish.polish_rounds = rounds;
  SurfaceMapReport rep;
  const Points before = x;
  polish_surface(domain, faces, area0, polish, x, rep);
  return !(x - before).isZero(0);
}

namespace {

// Where repair_flips may move a corner when it keeps areas: this fraction of the way from where
// it is to its neighbours' mean. The whole way alone inflated slivers of the input 30-100-fold
// (the sphere's development surface: 2.9 % face area change after a landmark flow's repair).
constexpr double kRepairFractions[] = {1.0 / 32, 1.0 / 16, 1.0 / 8, 1.0 / 4, 1.0 / 2, 3.0 / 4, 1};

// A face's chord area, negative when it is flipped (flipped_faces_in's test).
double signed_area(SurfaceDomain domain, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double s = domain == SurfaceDomain::sphere ? a.dot(b.cross(c)) : n(2);
  return s > 0 ? n.norm() / 2 : -n.norm() / 2;
}

}  // namespace

int repair_flips(const SurfaceDomainMoves& domain, const Triangles& f, const Eigen::VectorXd& area0, Points& x) {
  std::vector<int> flipped = domain.flipped(x, f);
  const int found = static_cast<int>(flipped.size());
  if (flipped.empty()) return 0;
  const bool sphere = domain.domain == SurfaceDomain::sphere, keep = area0.size() > 0;
  // each corner's neighbours listed twice (once per face on each side of the edge: the mean is
  // the same) and its faces
  std::vector<std::vector<int>> ring(static_cast<size_t>(x.rows())), star(static_cast<size_t>(x.rows()));
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      ring[static_cast<size_t>(f(t, k))].push_back(f(t, (k + 1) % 3));
      ring[static_cast<size_t>(f(t, k))].push_back(f(t, (k + 2) % 3));
      star[static_cast<size_t>(f(t, k))].push_back(static_cast<int>(t));
    }
  // the flipped faces of v's star and their sum |log(area / area0)| with v at p
  const auto cost = [&](Eigen::Index v, const Eigen::RowVector3d& p) {
    int flips = 0;
    double err = 0;
    for (int t : star[static_cast<size_t>(v)]) {
      Eigen::Vector3d c[3];
      for (int k = 0; k < 3; ++k) c[k] = f(t, k) == v ? p.transpose() : Eigen::Vector3d(x.row(f(t, k)).transpose());
      const double a = signed_area(domain.domain, c[0], c[1], c[2]);
      if (a > 0)
        err += keep && area0(t) > 0 ? std::abs(std::log(a / area0(t))) : 0;
      else
        ++flips;
    }
    return std::make_pair(flips, err);
  };
  for (int sweep = 0; sweep < 50 && !flipped.empty(); ++sweep) {
    for (int t : flipped)
      for (int k = 0; k < 3; ++k) {
        const Eigen::Index v = f(t, k);
        if ((!domain.fixed.empty() && domain.fixed[static_cast<size_t>(v)]) || (!sphere && domain.boundary[static_cast<size_t>(v)])) continue;
        Eigen::RowVector3d m = Eigen::RowVector3d::Zero();
        for (int w : ring[static_cast<size_t>(v)]) m += x.row(w);
        m /= static_cast<double>(ring[static_cast<size_t>(v)].size());
        // the sphere's points normalised onto it; the disk's lie inside it (a convex domain)
        Eigen::RowVector3d best;
        std::pair<int, double> least{std::numeric_limits<int>::max(), 0};
        for (double s : kRepairFractions) {
          if (!keep && s < 1) continue;  // the whole way
          Eigen::RowVector3d p = (1 - s) * x.row(v) + s * m;
          if (sphere) p.normalize();
          const auto c = cost(v, p);
          if (c < least) least = c, best = p;
        }
        x.row(v) = best;
      }
    flipped = domain.flipped(x, f);
  }
  return found;
}

}  // namespace vpm::detail
