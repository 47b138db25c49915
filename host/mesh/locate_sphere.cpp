// Directions located on a triangulation of the unit sphere (vpm/locate.hpp, SphereLocator).
#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <utility>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/locate.hpp"

namespace vpm {

namespace {

using Eigen::Vector3d;

// Walk steps before a query falls back to scanning every face.
int walk_limit(Eigen::Index faces) { return static_cast<int>(std::min<Eigen::Index>(faces, 4 * static_cast<Eigen::Index>(std::sqrt(static_cast<double>(faces))) + 64)); }

}  // namespace

SphereLocator::SphereLocator(const Points& sphere, const Triangles& faces) : x_(sphere), f_(faces) {
  const Eigen::Index n = x_.rows(), m = f_.rows();
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k)
      if (f_(t, k) < 0 || f_(t, k) >= n)
        throw InputError("sphere locator: face " + std::to_string(t) + " names vertex " + std::to_string(f_(t, k)) + " of " + std::to_string(n));
  across_.assign(3 * static_cast<size_t>(m), -1);
  std::map<std::pair<int, int>, int> edge;  // (a, b) of a face's edge a -> b
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) edge[{f_(t, k), f_(t, (k + 1) % 3)}] = static_cast<int>(3 * t + k);
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) {
      const auto it = edge.find({f_(t, (k + 1) % 3), f_(t, k)});
      if (it != edge.end()) across_[static_cast<size_t>(3 * t + k)] = it->second / 3;
    }
  n_ = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(m) / 24)));
  cells_.assign(6 * static_cast<size_t>(n_) * n_, -1);
  for (Eigen::Index t = 0; t < m; ++t) {
    const Vector3d c = (x_.row(f_(t, 0)) + x_.row(f_(t, 1)) + x_.row(f_(t, 2))).transpose();
    if (c.squaredNorm() > 0) cells_[static_cast<size_t>(cell_of(c))] = static_cast<int>(t);
  }
}

// The cube-map cell of direction p: the cube face of its largest coordinate, then the two others
// divided by it, on an n x n grid.
int SphereLocator::cell_of(const Vector3d& p) const {
  int axis = 0;
  p.cwiseAbs().maxCoeff(&axis);
  const double d = std::abs(p(axis));
  const int face = 2 * axis + (p(axis) < 0 ? 1 : 0);
  const double u = p((axis + 1) % 3) / d, v = p((axis + 2) % 3) / d;  // in [-1, 1]
  const int i = std::clamp(static_cast<int>((u + 1) / 2 * n_), 0, n_ - 1);
  const int j = std::clamp(static_cast<int>((v + 1) / 2 * n_), 0, n_ - 1);
  return (face * n_ + j) * n_ + i;
}

// s[k] = p.(corner k x corner k+1): all non-negative when p is in the face's cone.
bool SphereLocator::inside(int t, const Vector3d& p, double* s) const {
  const Vector3d a = x_.row(f_(t, 0)).transpose(), b = x_.row(f_(t, 1)).transpose(), c = x_.row(f_(t, 2)).transpose();
  s[0] = p.dot(a.cross(b));
  s[1] = p.dot(b.cross(c));
  s[2] = p.dot(c.cross(a));
  return s[0] >= 0 && s[1] >= 0 && s[2] >= 0 && p.dot(a + b + c) > 0;
}

SphereLocation SphereLocator::locate(const Vector3d& p, int hint) const {
  SphereLocation out;
  const int m = static_cast<int>(f_.rows());
  if (m == 0 || !(p.squaredNorm() > 0) || !p.allFinite()) return out;
  int t = hint >= 0 && hint < m ? hint : cells_[static_cast<size_t>(cell_of(p))];
  if (t < 0) t = 0;
  double s[3];
  bool found = false;
  const int limit = walk_limit(m);
  for (int step = 0; step < limit; ++step) {
    if (inside(t, p, s)) {
      found = true;
      break;
    }
    // across the edge whose plane separates p from the face most, alternating the tie-break
    // with the step so a walk on a non-Delaunay triangulation does not cycle
    int k = 0;
    for (int e = 1; e < 3; ++e)
      if (step % 2 ? s[e] <= s[k] : s[e] < s[k]) k = e;
    const int next = across_[static_cast<size_t>(3 * t + k)];
    if (next < 0 || s[k] >= 0) break;  // an open edge, or p behind the face (the antipode)
    t = next;
  }
  if (!found) {  // a flipped triangulation or a walk that did not end: every face
    double best = -1e300;
    for (int u = 0; u < m; ++u) {
      double su[3];
      if (inside(u, p, su)) {
        t = u, found = true, std::copy(su, su + 3, s);
        break;
      }
      const double worst = std::min({su[0], su[1], su[2]});
      if (p.dot(x_.row(f_(u, 0)).transpose()) > 0 && worst > best) best = worst, t = u, std::copy(su, su + 3, s);
    }
  }
  out.face = t;
  // corner k's weight is the plane of the opposite edge: a <- s[1], b <- s[2], c <- s[0]
  const double w[3] = {std::max(s[1], 0.0), std::max(s[2], 0.0), std::max(s[0], 0.0)};
  const double sum = w[0] + w[1] + w[2];
  for (int k = 0; k < 3; ++k) out.bary[k] = sum > 0 ? w[k] / sum : 1.0 / 3;
  return out;
}

std::vector<SphereLocation> SphereLocator::locate_all(const Points& points) const {
  const int k = static_cast<int>(points.rows());
  std::vector<SphereLocation> out(static_cast<size_t>(k));
  detail::parallel_for(k, 4096, [&](int begin, int end) {
    int hint = -1;
    for (int i = begin; i < end; ++i) {
      out[static_cast<size_t>(i)] = locate(points.row(i).transpose(), hint);
      hint = out[static_cast<size_t>(i)].face;
    }
  });
  return out;
}

}  // namespace vpm
