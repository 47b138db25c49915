// Simplification of a closed triangulated surface by half-edge collapses
// (map/surface_collapse.hpp).
#include "map/surface_collapse.hpp"

#include <algorithm>
#include <limits>
#include <string>

#include "vpm/error.hpp"

namespace vpm::detail {

std::vector<int> CollapsibleSurface::neighbours(int u) const {
  std::vector<int> out;
  for (int t : vf[static_cast<size_t>(u)])
    for (int c = 0; c < 3; ++c)
      if (F(t, c) != u) out.push_back(F(t, c));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

bool CollapsibleSurface::collapsible(int u, int v, const std::vector<int>& nu) const {
  int shared = 0;
  std::array<int, 2> wing{-1, -1};
  for (int t : vf[static_cast<size_t>(u)])
    if (has(t, v)) {
      if (shared == 2) return false;
      wing[static_cast<size_t>(shared++)] = F(t, 0) + F(t, 1) + F(t, 2) - u - v;
    }
  if (shared != 2 || wing[0] == wing[1]) return false;
  const std::vector<int> nv = neighbours(v);
  int common = 0;
  for (int w : nu)
    if (std::binary_search(nv.begin(), nv.end(), w)) {
      if (w != wing[0] && w != wing[1]) return false;
      ++common;
    }
  return common == 2;
}

void CollapsibleSurface::collapse(int u, int v, int pass) {
  Collapse c;
  c.u = u;
  c.v = v;
  c.pass = pass;
  c.first_moved = static_cast<int>(moved_faces.size());
  int k = 0;
  for (int t : vf[static_cast<size_t>(u)]) {
    if (has(t, v)) {
      c.dead[static_cast<size_t>(k++)] = t;
      face_alive[static_cast<size_t>(t)] = 0;
      for (int j = 0; j < 3; ++j)
        if (F(t, j) != u) erase(F(t, j), t);
    } else {
      for (int j = 0; j < 3; ++j)
        if (F(t, j) == u) F(t, j) = v;
      vf[static_cast<size_t>(v)].push_back(t);
      moved_faces.push_back(t);
    }
  }
  c.moved = static_cast<int>(moved_faces.size()) - c.first_moved;
  vf[static_cast<size_t>(u)].clear();
  alive[static_cast<size_t>(u)] = 0;
  --alive_count;
  log.push_back(c);
}

void CollapsibleSurface::restore(const Collapse& c) {
  for (int i = c.first_moved; i < c.first_moved + c.moved; ++i) {
    const int t = moved_faces[static_cast<size_t>(i)];
    for (int j = 0; j < 3; ++j)
      if (F(t, j) == c.v) F(t, j) = c.u;
    erase(c.v, t);
    vf[static_cast<size_t>(c.u)].push_back(t);
  }
  for (int t : c.dead) {
    face_alive[static_cast<size_t>(t)] = 1;
    for (int j = 0; j < 3; ++j) vf[static_cast<size_t>(F(t, j))].push_back(t);
  }
  alive[static_cast<size_t>(c.u)] = 1;
  ++alive_count;
}

void CollapsibleSurface::erase(int v, int t) {
  auto& l = vf[static_cast<size_t>(v)];
  l.erase(std::find(l.begin(), l.end(), t));
}

// Half-edge collapses in passes over an independent set (no two collapses of a pass touch the
// same ring) until 4 vertices are left, lightest first: each vertex carries the input area of
// the vertices collapsed into it (`weight`), and a vertex goes into its lightest neighbour, so
// the clusters grow evenly and every level's triangles can be both well shaped and of their
// share of the area. Returns the passes run.
int simplify(CollapsibleSurface& s, const Points& in, std::vector<double>& weight) {
  const int n = static_cast<int>(in.rows());
  std::vector<char> touched(static_cast<size_t>(n));
  std::vector<int> order;
  int pass = 0;
  while (s.alive_count > 4) {
    order.clear();
    for (int u = 0; u < n; ++u)
      if (s.alive[static_cast<size_t>(u)]) order.push_back(u);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return weight[static_cast<size_t>(a)] < weight[static_cast<size_t>(b)]; });
    int done = 0;
    for (int attempt = 0; attempt < 2 && done == 0; ++attempt) {
      const size_t degree_cap = attempt == 0 ? 12 : std::numeric_limits<size_t>::max();
      std::fill(touched.begin(), touched.end(), 0);
      for (int u : order) {
        if (s.alive_count <= 4) break;
        if (touched[static_cast<size_t>(u)]) continue;
        const std::vector<int> nu = s.neighbours(u);
        std::vector<int> candidates = nu;
        std::sort(candidates.begin(), candidates.end(), [&](int a, int b) {
          const double wa = weight[static_cast<size_t>(a)], wb = weight[static_cast<size_t>(b)];
          if (wa != wb) return wa < wb;
          return (in.row(a) - in.row(u)).squaredNorm() < (in.row(b) - in.row(u)).squaredNorm();
        });
        for (int v : candidates) {
          if (touched[static_cast<size_t>(v)] && attempt == 0) continue;
          if (nu.size() + s.neighbours(v).size() - 4 > degree_cap) continue;
          if (!s.collapsible(u, v, nu)) continue;
          s.collapse(u, v, pass);
          weight[static_cast<size_t>(v)] += weight[static_cast<size_t>(u)];
          touched[static_cast<size_t>(u)] = touched[static_cast<size_t>(v)] = 1;
          for (int w : nu) touched[static_cast<size_t>(w)] = 1;
          ++done;
          break;
        }
      }
    }
    if (done == 0)
      throw NumericalError("sphere map: the boundary surface could not be simplified below " +
                           std::to_string(s.alive_count) + " vertices (is it a closed genus-0 surface?)");
    ++pass;
  }
  return pass;
}

}  // namespace vpm::detail
