#pragma once
// Private: a closed triangulated surface simplified by half-edge collapses that can be undone
// one by one (the hierarchy behind progressive_sphere, map/sphere_steps.hpp).
#include <algorithm>
#include <array>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm::detail {

/// One half-edge collapse, as CollapsibleSurface::log records it.
struct Collapse {
  int u = -1, v = -1;             ///< u was collapsed into v
  std::array<int, 2> dead{};      ///< the two faces that had edge uv
  int first_moved = 0, moved = 0; ///< faces that had u (not v): moved_faces[first_moved, +moved)
  int pass = 0;                   ///< simplify()'s pass (a level of the hierarchy)
};

/// The surface's faces (F, kept oriented), each vertex's alive faces, and the log of the
/// collapses done, which restore() undoes in reverse order.
class CollapsibleSurface {
 public:
  CollapsibleSurface(const Triangles& f, int n)
      : F(f), vf(static_cast<size_t>(n)), alive(static_cast<size_t>(n), 1), face_alive(static_cast<size_t>(f.rows()), 1) {
    for (Eigen::Index i = 0; i < F.rows(); ++i)
      for (int c = 0; c < 3; ++c) vf[static_cast<size_t>(F(i, c))].push_back(static_cast<int>(i));
    alive_count = n;
  }

  Triangles F;
  std::vector<std::vector<int>> vf;  // alive faces of each vertex
  std::vector<char> alive, face_alive;
  int alive_count = 0;
  std::vector<int> moved_faces;
  std::vector<Collapse> log;

  std::vector<int> neighbours(int u) const {
    std::vector<int> out;
    for (int t : vf[static_cast<size_t>(u)])
      for (int c = 0; c < 3; ++c)
        if (F(t, c) != u) out.push_back(F(t, c));
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
    return out;
  }

  bool has(int t, int v) const { return F(t, 0) == v || F(t, 1) == v || F(t, 2) == v; }

  // The link condition of edge uv: exactly two faces share it and the rings of u and v meet
  // only in those faces' third vertices, so the collapse keeps a simplicial sphere.
  bool collapsible(int u, int v, const std::vector<int>& nu) const {
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

  void collapse(int u, int v, int pass) {
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

  void restore(const Collapse& c) {
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

 private:
  void erase(int v, int t) {
    auto& l = vf[static_cast<size_t>(v)];
    l.erase(std::find(l.begin(), l.end(), t));
  }
};

/// Half-edge collapses in passes over independent sets until 4 vertices are left, lightest
/// first (`weight`: the input area of each vertex, summed into the vertex it is collapsed into).
/// Returns the passes run; NumericalError when no edge can be collapsed (not a genus-0 sphere).
int simplify(CollapsibleSurface& s, const Points& in, std::vector<double> weight);

}  // namespace vpm::detail
