// A sphere map of a closed genus-0 surface from its two ends (map/sphere_steps.hpp,
// axial_sphere): the surface as a cylinder between two poles, its height equal-area.
//
// The conformal sphere map of a tube of length l and radius r shrinks one end by e^(-l / r):
// the coil of bench/shapes (l / r about 50) arrives folded, and the progressive embedding, which
// does not fold, leaves it so uneven (the ends 13 times too small, the middle twice too large)
// that the area flow on the sphere stalls at 107 %. Here, for the two vertices a and b farthest
// apart (two Dijkstra sweeps over the edges), with their stars removed the surface is an
// annulus; on it
//   1. the height: the harmonic function phi, 0 on a's ring and 1 on b's (clamped cotangent
//      weights, positive, so every level set is one loop around the axis);
//   2. the angle: the harmonic one-form with period one around the annulus, with the same
//      weights (Gortler, Gotsman & Thurston 2006: two such coordinates embed an annulus in a
//      flat cylinder). Its closed representative eta comes from phi's conjugate (the flux
//      w_ij (phi_j - phi_i) integrated across the faces, averaged to the vertices); the
//      harmonic one is eta + dh with L h = div eta;
//   3. on the sphere: longitude 2 pi x angle, and latitude from phi's order: a vertex's
//      z = 1 - 2 F, F the share of the surface's area (vertex shares) below its level, so every
//      band between two levels gets exactly its area (Archimedes), a on the north pole, b on
//      the south.
// A monotone function of the height keeps the cylinder's embedding, so no chord triangle faces
// inwards for a fine enough mesh (checked by the caller). The bands' shares are exact; within a
// band the angle is conformal, not equal-area (the inside of the coil's turns 27 % denser than
// the outside): the area flow on the sphere removes what is left.
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <numeric>
#include <queue>
#include <unordered_map>
#include <vector>

#include "map/sphere_steps.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

namespace {

// The vertices' neighbours (sorted, unique) from the triangles.
std::vector<std::vector<int>> neighbours(int k, const Triangles& f) {
  std::vector<std::vector<int>> nb(static_cast<size_t>(k));
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int j = 0; j < 3; ++j) {
      nb[static_cast<size_t>(f(t, j))].push_back(f(t, (j + 1) % 3));
      nb[static_cast<size_t>(f(t, j))].push_back(f(t, (j + 2) % 3));
    }
  for (auto& n : nb) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
  return nb;
}

// The vertex farthest from `from` along the edges (Dijkstra with the input's edge lengths).
int farthest(const Points& in, const std::vector<std::vector<int>>& nb, int from) {
  const size_t k = nb.size();
  std::vector<double> d(k, std::numeric_limits<double>::infinity());
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> q;
  d[static_cast<size_t>(from)] = 0;
  q.emplace(0.0, from);
  int last = from;
  while (!q.empty()) {
    const auto [di, i] = q.top();
    q.pop();
    if (di > d[static_cast<size_t>(i)]) continue;
    last = i;
    for (int j : nb[static_cast<size_t>(i)]) {
      const double dj = di + (in.row(i) - in.row(j)).norm();
      if (dj < d[static_cast<size_t>(j)]) {
        d[static_cast<size_t>(j)] = dj;
        q.emplace(dj, j);
      }
    }
  }
  return last;  // popped last: the largest distance
}

uint64_t edge_key(int i, int j) { return (static_cast<uint64_t>(static_cast<uint32_t>(i)) << 32) | static_cast<uint32_t>(j); }

// Solves L_FF x_F = rhs_F with the rows in `fixed` held at 0 (Eigen's LDLT); false when the
// solve failed.
bool neumann_solve(const SpMat& L, const std::vector<char>& fixed, const Eigen::VectorXd& rhs, Eigen::VectorXd& x) {
  const Eigen::MatrixXd zero = Eigen::MatrixXd::Zero(L.rows(), 1), source = rhs;
  const FreeRows fr = free_rows(L, fixed, zero, &source);
  Eigen::SimplicialLDLT<SpMat> ldlt(fr.a);
  if (ldlt.info() != Eigen::Success) return false;
  const Eigen::VectorXd y = ldlt.solve(fr.rhs.col(0));
  if (ldlt.info() != Eigen::Success || !y.allFinite()) return false;
  x = Eigen::VectorXd::Zero(L.rows());
  for (Eigen::Index i = 0; i < L.rows(); ++i)
    if (fr.idx[static_cast<size_t>(i)] >= 0) x(i) = y(fr.idx[static_cast<size_t>(i)]);
  return true;
}

// The surface with the poles' stars removed: its triangles, its clamped cotangent Laplacian
// (the poles' rows empty) and which vertices ring each pole.
struct Annulus {
  int a = -1, b = -1;
  std::vector<char> ring;  ///< 1: a's ring, 2: b's ring
  Triangles f;
  SpMat L;
  double weight(int i, int j) const { return -L.coeff(i, j); }
};

// The annulus between the two vertices farthest apart; false when their rings touch.
bool annulus(const Points& in, const Triangles& f, const std::vector<std::vector<int>>& nb, Annulus& an) {
  const int k = static_cast<int>(in.rows());
  const int a = farthest(in, nb, farthest(in, nb, 0)), b = farthest(in, nb, a);
  const auto& na = nb[static_cast<size_t>(a)];
  if (a == b || std::binary_search(na.begin(), na.end(), b)) return false;
  an.a = a;
  an.b = b;
  an.ring.assign(static_cast<size_t>(k), 0);
  for (int j : na) an.ring[static_cast<size_t>(j)] |= 1;
  for (int j : nb[static_cast<size_t>(b)]) an.ring[static_cast<size_t>(j)] |= 2;
  if (std::find(an.ring.begin(), an.ring.end(), 3) != an.ring.end()) return false;
  std::vector<Eigen::Index> keep;
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    if ((f.row(t).array() != a).all() && (f.row(t).array() != b).all()) keep.push_back(t);
  an.f.resize(static_cast<Eigen::Index>(keep.size()), 3);
  for (size_t t = 0; t < keep.size(); ++t) an.f.row(static_cast<Eigen::Index>(t)) = f.row(keep[t]);
  constexpr double kClamp = 1e-3;  // the conformal map's clamped weights: all positive
  an.L = cot_laplacian(in, an.f, kClamp);
  return an.f.rows() > 0;
}

// The height: harmonic on the annulus, 0 on a's ring and 1 on b's.
bool height(const Annulus& an, Eigen::MatrixXd& phi) {
  const int k = static_cast<int>(an.ring.size());
  std::vector<char> fixed(static_cast<size_t>(k), 0);
  phi = Eigen::MatrixXd::Zero(k, 1);
  fixed[static_cast<size_t>(an.a)] = fixed[static_cast<size_t>(an.b)] = 1;
  phi(an.b) = 1;
  for (int i = 0; i < k; ++i)
    if (an.ring[static_cast<size_t>(i)]) {
      fixed[static_cast<size_t>(i)] = 1;
      phi(i) = an.ring[static_cast<size_t>(i)] == 2 ? 1.0 : 0.0;
    }
  return dirichlet_solve(an.L, fixed, phi);
}

// The conjugate of the height per face, in turns: its flux w_ij (phi_j - phi_i) integrated
// across the faces breadth first, divided by the flux around a's ring. False when the annulus
// is not connected or carries no flux.
bool conjugate_turns(const Annulus& an, const std::vector<std::vector<int>>& nb, const Eigen::MatrixXd& phi,
                     Eigen::VectorXd& psi) {
  const Triangles& fa = an.f;
  std::unordered_map<uint64_t, Eigen::Index> face_of;
  face_of.reserve(static_cast<size_t>(3 * fa.rows()));
  for (Eigen::Index t = 0; t < fa.rows(); ++t)
    for (int j = 0; j < 3; ++j) face_of[edge_key(fa(t, j), fa(t, (j + 1) % 3))] = t;
  double period = 0;
  for (size_t i = 0; i < an.ring.size(); ++i)
    if (an.ring[i] == 1)
      for (int j : nb[i])
        if (j != an.a) period += an.weight(static_cast<int>(i), j) * (phi(j) - phi(static_cast<Eigen::Index>(i)));
  if (!(std::abs(period) > 0)) return false;
  psi = Eigen::VectorXd::Constant(fa.rows(), std::numeric_limits<double>::quiet_NaN());
  std::queue<Eigen::Index> open;
  psi(0) = 0;
  open.push(0);
  while (!open.empty()) {
    const Eigen::Index t = open.front();
    open.pop();
    for (int j = 0; j < 3; ++j) {
      const int u = fa(t, j), v = fa(t, (j + 1) % 3);
      const auto g = face_of.find(edge_key(v, u));
      if (g == face_of.end() || !std::isnan(psi(g->second))) continue;
      psi(g->second) = psi(t) + an.weight(u, v) * (phi(v) - phi(u));
      open.push(g->second);
    }
  }
  psi /= period;
  return psi.allFinite();
}

// The angle in turns per vertex: the faces' conjugate averaged on the circle, then made the
// harmonic one-form eta + dh (L h = div eta, eta_ij the wrapped difference of the averages).
bool angle(const Annulus& an, const std::vector<std::vector<int>>& nb, const Eigen::MatrixXd& phi,
           Eigen::VectorXd& turns) {
  Eigen::VectorXd psi;
  if (!conjugate_turns(an, nb, phi, psi)) return false;
  const int k = static_cast<int>(an.ring.size());
  Eigen::VectorXd cs = Eigen::VectorXd::Zero(k), sn = Eigen::VectorXd::Zero(k);
  for (Eigen::Index t = 0; t < an.f.rows(); ++t)
    for (int j = 0; j < 3; ++j) {
      cs(an.f(t, j)) += std::cos(2 * M_PI * psi(t));
      sn(an.f(t, j)) += std::sin(2 * M_PI * psi(t));
    }
  turns.resize(k);
  for (int i = 0; i < k; ++i) turns(i) = std::atan2(sn(i), cs(i)) / (2 * M_PI);
  Eigen::VectorXd div = Eigen::VectorXd::Zero(k);
  for (int i = 0; i < k; ++i) {
    if (i == an.a || i == an.b) continue;
    for (int j : nb[static_cast<size_t>(i)]) {
      if (j == an.a || j == an.b) continue;
      const double d = turns(j) - turns(i);
      div(i) += an.weight(i, j) * (d - std::round(d));
    }
  }
  std::vector<char> held(static_cast<size_t>(k), 0);
  held[static_cast<size_t>(an.a)] = held[static_cast<size_t>(an.b)] = 1;
  held[static_cast<size_t>(nb[static_cast<size_t>(an.a)].front())] = 1;  // h is defined up to a constant
  Eigen::VectorXd h;
  if (!neumann_solve(an.L, held, div, h)) return false;
  turns += h;
  return true;
}

// Each vertex's share of the area below its height (vertices of equal height, a pole's ring,
// share one value), a's at the bottom and b's at the top.
Eigen::VectorXd area_below(const Annulus& an, Eigen::MatrixXd phi, const Eigen::VectorXd& share) {
  const int k = static_cast<int>(phi.rows());
  phi(an.a) = -1;
  phi(an.b) = 2;
  std::vector<int> order(static_cast<size_t>(k));
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return phi(x) < phi(y); });
  Eigen::VectorXd below(k);
  double acc = 0;
  for (size_t i = 0; i < order.size();) {
    size_t e = i;
    double s = 0;
    while (e < order.size() && phi(order[e]) == phi(order[i])) s += share(order[e++]);
    for (size_t g = i; g < e; ++g) below(order[g]) = acc + 0.5 * s;
    acc += s;
    i = e;
  }
  return below / acc;
}

}  // namespace

Points axial_sphere(const Points& in, const Triangles& f, AxialStats* stats) {
  const auto t0 = Clock::now();
  const int k = static_cast<int>(in.rows());
  if (k < 8) return Points();
  const std::vector<std::vector<int>> nb = neighbours(k, f);
  Annulus an;
  Eigen::MatrixXd phi;
  Eigen::VectorXd turns;
  if (!annulus(in, f, nb, an) || !height(an, phi) || !angle(an, nb, phi, turns)) return Points();
  const Eigen::VectorXd below = area_below(an, phi, vertex_area_shares(in, f));
  Points s(k, 3);
  for (int i = 0; i < k; ++i) {
    const double z = std::clamp(1 - 2 * below(i), -1.0, 1.0);
    const double r = std::sqrt(std::max(0.0, 1 - z * z)), lon = 2 * M_PI * turns(i);
    s.row(i) << r * std::cos(lon), r * std::sin(lon), z;
  }
  s.row(an.a) << 0, 0, 1;
  s.row(an.b) << 0, 0, -1;
  if (2 * flipped_sphere_triangles(s, f) > f.rows()) s.col(1) *= -1;  // the angle ran the other way
  if (stats) {
    stats->north = an.a;
    stats->south = an.b;
    stats->seconds = seconds_since(t0);
  }
  return s;
}

}  // namespace vpm::detail
