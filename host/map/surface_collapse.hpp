#pragma once
// Private: a closed triangulated surface simplified by half-edge collapses that can be undone
// one by one (the hierarchy behind progressive_sphere, map/sphere_steps.hpp).
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

  /// The vertices sharing a face with u, sorted.
  std::vector<int> neighbours(int u) const;
  bool has(int t, int v) const { return F(t, 0) == v || F(t, 1) == v || F(t, 2) == v; }
  /// The link condition of edge uv (nu: neighbours(u)): exactly two faces share it and the
  /// rings of u and v meet only in those faces' third vertices, so the collapse keeps a
  /// simplicial sphere.
  bool collapsible(int u, int v, const std::vector<int>& nu) const;
  /// Collapses u into v (the two faces of edge uv die, u's other faces take v) and logs it.
  void collapse(int u, int v, int pass);
  /// Undoes c, which must be the last collapse not yet undone.
  void restore(const Collapse& c);

 private:
  void erase(int v, int t);
};

/// Half-edge collapses in passes over independent sets until 4 vertices are left, lightest
/// first. `weight` in: the input area of each vertex; out: each vertex's plus that of the
/// vertices collapsed into it (the 4 left hold everything). Returns the passes run;
/// NumericalError when no edge can be collapsed (not a genus-0 sphere).
int simplify(CollapsibleSurface& s, const Points& in, std::vector<double>& weight);

}  // namespace vpm::detail
