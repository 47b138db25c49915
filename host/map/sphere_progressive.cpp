// A sphere embedding of a closed genus-0 surface that cannot fold through precision loss
// (map/sphere_steps.hpp, progressive_sphere): the surface is simplified by half-edge collapses
// down to a tetrahedron, the tetrahedron is put on the sphere, and the collapses are undone one
// by one, each restored vertex placed in the kernel of its ring next to the vertex it had been
// collapsed into and every move checked to keep all its triangles facing outwards (the idea of
// Praun & Hoppe 2003, "Spherical parametrization and remeshing"). After each level the vertices
// are relaxed on a barrier energy of shape and area, again only by moves that keep every
// triangle valid, so the result is a bijection onto the sphere whatever the shape's
// proportions: a conformal map of a long tube shrinks its far end by e^(-length / radius), below
// double precision, and flips triangles there.
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "map/sphere_steps.hpp"
#include "map/surface_collapse.hpp"
#include "vpm/error.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

using Vec = Eigen::Vector3d;

class Embedding {
 public:
  Embedding(CollapsibleSurface& s, int n) : s_(s), P(Points::Zero(n, 3)) {}

  // The tetrahedron left by simplify() on a regular tetrahedron of the sphere, facing outwards.
  void base() {
    std::vector<int> v;
    for (size_t i = 0; i < s_.alive.size(); ++i)
      if (s_.alive[i]) v.push_back(static_cast<int>(i));
    const double k = 1.0 / std::sqrt(3.0);
    const Vec corner[4] = {Vec(k, k, k), Vec(k, -k, -k), Vec(-k, k, -k), Vec(-k, -k, k)};
    for (int i = 0; i < 4; ++i) P.row(v[static_cast<size_t>(i)]) = corner[i].transpose();
    if (!star_valid(v[0])) {
      P.row(v[0]).swap(P.row(v[1]));
    }
    if (!star_valid(v[0]) || !star_valid(v[1]) || !star_valid(v[2]) || !star_valid(v[3]))
      throw NumericalError("sphere map: the simplified surface is not a tetrahedron");
  }

  // Undoes collapse c: u is placed next to v inside the kernel of its ring, in the direction
  // and at the distance (the largest valid one of a halving sequence) that leave the triangles
  // around u and v fattest; then u, v and their rings are relaxed.
  void split(const Collapse& c) {
    s_.restore(c);
    const Vec p = P.row(c.v).transpose();
    double scale = 1e300;
    for (int w : s_.neighbours(c.v))
      if (w != c.u) scale = std::min(scale, (P.row(w).transpose() - p).norm());
    // In the limit of u next to v only the two triangles with edge uv constrain the direction:
    // each det is linear in u's displacement; the bisector of their gradients (in the plane
    // tangent at v) is the middle of the wedge of valid directions.
    P.row(c.u) = p.transpose();
    Vec mid = Vec::Zero();
    for (int t : c.dead) {
      Vec g = det_gradient(t, c.u);
      g -= g.dot(p) * p;
      if (g.norm() > 0) mid += g.normalized();
    }
    const Vec t1 = p.unitOrthogonal(), t2 = p.cross(t1);
    constexpr int kDirections = 64, kHalvings = 50;
    double best_q = 0;
    Vec best = p;
    for (int a = -1; a < kDirections; ++a) {
      const Vec d = a < 0 ? mid : std::cos(2 * M_PI * a / kDirections) * t1 + std::sin(2 * M_PI * a / kDirections) * t2;
      if (!(d.norm() > 0)) continue;
      for (int j = 0; j < kHalvings; ++j) {
        P.row(c.u) = (p + 0.5 * scale * std::ldexp(1.0, -j) * d.normalized()).normalized().transpose();
        const double q = std::min(star_quality(c.u), star_quality(c.v));
        if (q > 0) {
          if (q > best_q) {
            best_q = q;
            best = P.row(c.u).transpose();
          }
          break;
        }
      }
    }
    if (!(best_q > 0))
      throw NumericalError("sphere map: no position keeps the triangles around restored vertex " + std::to_string(c.u) +
                           " facing outwards");
    P.row(c.u) = best.transpose();
    for (int k = 0; k < 2; ++k) {
      std::vector<int> ring = s_.neighbours(c.u);
      for (int w : s_.neighbours(c.v)) ring.push_back(w);
      relax(c.u);
      relax(c.v);
      for (int w : ring) relax(w);
    }
  }

  // Lowers the energy of w's star by a few projected gradient steps, each kept only when every
  // triangle stays valid (the energy is a barrier: it grows without bound as a triangle thins).
  // Energy per triangle t: alpha (sum of squared edges) / (4 sqrt 3 A) (1 for an equilateral
  // triangle: shape) + A / T + T / A (area; T the triangle's share of the current sphere area,
  // from the input area its corners stand for). Returns whether it moved.
  bool relax(int w) {
    const Vec x0 = P.row(w).transpose();
    double e0 = star_energy(w);
    if (!std::isfinite(e0)) return false;
    bool moved = false;
    for (int it = 0; it < 3; ++it) {
      const Vec x = P.row(w).transpose();
      Vec g = star_gradient(w);
      g -= g.dot(x) * x;
      const double gn = g.norm();
      if (!(gn > 0)) break;
      double h = 1e300;
      for (int v : s_.neighbours(w)) h = std::min(h, (P.row(v).transpose() - x).norm());
      double step = 0.25 * h / gn;
      bool ok = false;
      for (int ls = 0; ls < 12; ++ls, step *= 0.5) {
        P.row(w) = (x - step * g).normalized().transpose();
        const double e = star_energy(w);
        if (e < e0) {
          e0 = e;
          ok = true;
          break;
        }
      }
      if (!ok) {
        P.row(w) = x.transpose();
        break;
      }
      moved = true;
    }
    if (!moved) P.row(w) = x0.transpose();
    return moved;
  }

  void sweep() {
    for (size_t w = 0; w < s_.alive.size(); ++w)
      if (s_.alive[w]) relax(static_cast<int>(w));
  }

  // Cluster weights and triangle targets for the current level: call after each level's splits.
  void set_targets() {
    double wsum = 0, area = 0;
    for (size_t t = 0; t < s_.face_alive.size(); ++t)
      if (s_.face_alive[t]) {
        wsum += corner_weight(static_cast<int>(t));
        area += chord_area(static_cast<int>(t));
      }
    area_per_weight_ = area / wsum;
  }

  // d det(face t) / d position of its vertex w.
  Vec det_gradient(int t, int w) const {
    const Vec a = P.row(s_.F(t, 0)).transpose(), b = P.row(s_.F(t, 1)).transpose(), c = P.row(s_.F(t, 2)).transpose();
    if (s_.F(t, 0) == w) return b.cross(c);
    if (s_.F(t, 1) == w) return c.cross(a);
    return a.cross(b);
  }

  bool star_valid(int w) const { return star_quality(w) > 0; }

  double corner_weight(int t) const {
    return weight[static_cast<size_t>(s_.F(t, 0))] + weight[static_cast<size_t>(s_.F(t, 1))] +
           weight[static_cast<size_t>(s_.F(t, 2))];
  }

  // Half the volume form a.(b x c) of the chord triangle: its area times the distance of its
  // plane from the centre (the area for a small triangle; smaller for one spanning the sphere).
  double chord_area(int t) const {
    const Vec a = P.row(s_.F(t, 0)).transpose(), b = P.row(s_.F(t, 1)).transpose(), c = P.row(s_.F(t, 2)).transpose();
    return 0.5 * a.dot(b.cross(c));
  }

  // The star energy of w (see relax); infinite when a triangle is not valid.
  double star_energy(int w) const {
    double e = 0;
    for (int t : s_.vf[static_cast<size_t>(w)]) {
      const Vec a = P.row(s_.F(t, 0)).transpose(), b = P.row(s_.F(t, 1)).transpose(), c = P.row(s_.F(t, 2)).transpose();
      const double A = 0.5 * a.dot(b.cross(c));
      const double S = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
      if (!(2 * A / S > kThin)) return std::numeric_limits<double>::infinity();  // face_quality 0
      const double T = area_per_weight_ * corner_weight(t);
      e += kShape * S / (4 * std::sqrt(3.0) * A) + A / T + T / A;
    }
    return e;
  }

  // Gradient of star_energy with respect to w's position.
  Vec star_gradient(int w) const {
    Vec g = Vec::Zero();
    for (int t : s_.vf[static_cast<size_t>(w)]) {
      int k = 0;
      while (s_.F(t, k) != w) ++k;
      const Vec x = P.row(w).transpose(), b = P.row(s_.F(t, (k + 1) % 3)).transpose(),
                c = P.row(s_.F(t, (k + 2) % 3)).transpose();
      const double A = 0.5 * x.dot(b.cross(c));
      const Vec dA = 0.5 * b.cross(c);
      const double S = (b - x).squaredNorm() + (c - x).squaredNorm() + (c - b).squaredNorm();
      const Vec dS = 2 * (x - b) + 2 * (x - c);
      const double T = area_per_weight_ * corner_weight(t);
      g += kShape / (4 * std::sqrt(3.0)) * (dS / A - S * dA / (A * A)) + dA * (1 / T - T / (A * A));
    }
    return g;
  }

  // The smallest face_quality of w's triangles.
  double star_quality(int w) const {
    double q = 1e300;
    for (int t : s_.vf[static_cast<size_t>(w)]) q = std::min(q, face_quality(t));
    return q;
  }

  // a.(b x c) / (sum of squared edges): a shape measure of the chord triangle (about 0.29 for a
  // small equilateral one), positive when it faces outwards; 0 when inverted or thinner than
  // 1e-10 (for a small triangle about the sine of its smallest angle).
  double face_quality(int t) const {
    const Vec a = P.row(s_.F(t, 0)).transpose(), b = P.row(s_.F(t, 1)).transpose(), c = P.row(s_.F(t, 2)).transpose();
    const double e = (b - a).squaredNorm() + (c - b).squaredNorm() + (a - c).squaredNorm();
    const double q = a.dot(b.cross(c)) / e;
    return q > kThin ? q : 0.0;
  }

  static constexpr double kShape = 1.0, kThin = 1e-10;

 private:
  CollapsibleSurface& s_;
  double area_per_weight_ = 1;

 public:
  Points P;
  std::vector<double> weight;  // input area each alive vertex stands for
};

}  // namespace

Points progressive_sphere(const Points& in, const Triangles& f, ProgressiveStats* stats) {
  const auto t0 = Clock::now();
  const int n = static_cast<int>(in.rows());
  if (n < 4 || f.rows() != 2 * static_cast<Eigen::Index>(n) - 4)
    throw InputError("sphere map: the boundary surface (" + std::to_string(n) + " vertices, " +
                     std::to_string(f.rows()) + " triangles) is not a closed genus-0 surface");
  CollapsibleSurface s(f, n);
  const Eigen::VectorXd share = vertex_area_shares(in, f);
  Embedding e(s, n);
  e.weight.assign(share.data(), share.data() + n);
  const int passes = simplify(s, in, e.weight);
  e.base();
  constexpr int kSweepsPerLevel = 3, kFinalSweeps = 20;
  size_t next = s.log.size();
  int sweeps = 0;
  for (int pass = passes - 1; pass >= 0; --pass) {
    e.set_targets();
    while (next > 0 && s.log[next - 1].pass == pass) {
      const Collapse& c = s.log[--next];
      e.weight[static_cast<size_t>(c.v)] -= e.weight[static_cast<size_t>(c.u)];
      e.split(c);
    }
    e.set_targets();
    for (int k = 0; k < kSweepsPerLevel; ++k, ++sweeps) e.sweep();
  }
  for (int k = 0; k < kFinalSweeps; ++k, ++sweeps) e.sweep();
  if (stats) {
    stats->passes = passes;
    stats->collapses = static_cast<int>(s.log.size());
    stats->sweeps = sweeps;
    stats->seconds = seconds_since(t0);
  }
  return e.P;
}

}  // namespace vpm::detail
