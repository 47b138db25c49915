#include "vpm/topology.hpp"

#include <algorithm>
#include <array>
#include <numeric>
#include <string>
#include <unordered_map>

#include "core/group_by_key.hpp"
#include "mesh/face_table.hpp"
#include "mesh/tet_grid.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace {
// Faces of tet (a,b,c,d) with outward orientation for a positive tet.
constexpr int kFace[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

int find_root(std::vector<int>& p, int x) {
  while (p[x] != x) {
    p[x] = p[p[x]];
    x = p[x];
  }
  return x;
}
}  // namespace

namespace detail {
Triangles boundary_faces(const FaceTable& ft, const Tets& tets, std::vector<int>* face_tet) {
  std::vector<int> owner;
  ft.for_each_group([&](int first, int count) {
    if (count == 1) owner.push_back(ft.entries[static_cast<size_t>(first)].slot);
  });
  Triangles tri(static_cast<Eigen::Index>(owner.size()), 3);
  for (size_t i = 0; i < owner.size(); ++i) {
    const int t = owner[i] / 4, k = owner[i] % 4;
    for (int c = 0; c < 3; ++c) tri(static_cast<Eigen::Index>(i), c) = tets(t, kFace[k][c]);
    owner[i] = t;
  }
  if (face_tet) *face_tet = std::move(owner);
  return tri;
}

int nonmanifold_faces(const FaceTable& ft) {
  int bad = 0;
  ft.for_each_group([&](int, int count) { bad += count > 2; });
  return bad;
}
}  // namespace detail

Triangles boundary_faces(const Tets& tets, std::vector<int>* face_tet) {
  return detail::boundary_faces(detail::face_table(tets), tets, face_tet);
}

int nonmanifold_faces(const Tets& tets) { return detail::nonmanifold_faces(detail::face_table(tets)); }

std::vector<char> boundary_vertex_mask(int num_vertices, const Triangles& faces) {
  std::vector<char> m(static_cast<size_t>(num_vertices), 0);
  for (int i = 0; i < faces.rows(); ++i)
    for (int c = 0; c < 3; ++c) m[static_cast<size_t>(faces(i, c))] = 1;
  return m;
}

TetTopology tet_topology(int num_vertices, const Tets& tets) {
  if (tets.size() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= num_vertices))
    throw InputError("tet_topology: the tets use vertices outside 0.." + std::to_string(num_vertices - 1));
  TetTopology t;
  t.neighbours = detail::tet_neighbors(tets, &t.boundary);
  t.boundary_vertex = boundary_vertex_mask(num_vertices, t.boundary);
  return t;
}

Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> unique_edges(const Tets& tets) {
  std::vector<std::pair<int, int>> e;
  e.reserve(static_cast<size_t>(tets.rows()) * 6);
  for (int t = 0; t < tets.rows(); ++t)
    for (int a = 0; a < 4; ++a)
      for (int b = a + 1; b < 4; ++b) {
        int i = tets(t, a), j = tets(t, b);
        e.emplace_back(std::min(i, j), std::max(i, j));
      }
  std::sort(e.begin(), e.end());
  e.erase(std::unique(e.begin(), e.end()), e.end());
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> out(static_cast<Eigen::Index>(e.size()), 2);
  for (size_t i = 0; i < e.size(); ++i) {
    out(static_cast<Eigen::Index>(i), 0) = e[i].first;
    out(static_cast<Eigen::Index>(i), 1) = e[i].second;
  }
  return out;
}

Incidence vertex_tet_incidence(int num_vertices, const Tets& tets) {
  Incidence inc;
  detail::group_by_key(
      static_cast<int>(tets.rows()), static_cast<size_t>(num_vertices),
      [&](int t, auto&& visit) {
        for (int c = 0; c < 4; ++c) visit(static_cast<size_t>(tets(t, c)));
      },
      inc.offset, inc.tet_of);
  return inc;
}

std::vector<char> vertices_near_tets(int num_vertices, const Tets& tets, const std::vector<int>& seed_tets,
                                     int rings) {
  // level: the ring a vertex was found in; pass r takes every tet with a vertex found before it
  std::vector<int> level(static_cast<size_t>(num_vertices), -1);
  for (int t : seed_tets)
    for (int c = 0; c < 4; ++c) level[static_cast<size_t>(tets(t, c))] = 0;
  for (int r = 1; r <= rings; ++r)
    for (Eigen::Index t = 0; t < tets.rows(); ++t) {
      const int* q = &tets(t, 0);
      bool touches = false;
      for (int c = 0; c < 4; ++c) touches = touches || (level[q[c]] >= 0 && level[q[c]] < r);
      if (touches)
        for (int c = 0; c < 4; ++c)
          if (level[q[c]] < 0) level[q[c]] = r;
    }
  std::vector<char> near(static_cast<size_t>(num_vertices));
  for (int v = 0; v < num_vertices; ++v) near[static_cast<size_t>(v)] = level[static_cast<size_t>(v)] >= 0;
  return near;
}

std::vector<int> vertex_components(int num_vertices, const Tets& tets, int* count) {
  std::vector<int> p(static_cast<size_t>(num_vertices));
  std::iota(p.begin(), p.end(), 0);
  for (int t = 0; t < tets.rows(); ++t)
    for (int c = 1; c < 4; ++c) {
      int a = find_root(p, tets(t, 0)), b = find_root(p, tets(t, c));
      if (a != b) p[static_cast<size_t>(a)] = b;
    }
  std::vector<int> id(static_cast<size_t>(num_vertices), -1), comp(static_cast<size_t>(num_vertices));
  int n = 0;
  for (int v = 0; v < num_vertices; ++v) {
    int r = find_root(p, v);
    if (id[static_cast<size_t>(r)] < 0) id[static_cast<size_t>(r)] = n++;
    comp[static_cast<size_t>(v)] = id[static_cast<size_t>(r)];
  }
  if (count) *count = n;
  return comp;
}

SurfaceTopology surface_topology(int num_vertices, const Triangles& faces) {
  SurfaceTopology s;
  s.faces = static_cast<int>(faces.rows());
  // edges with their incident face count
  std::vector<std::array<int, 3>> e;  // (min, max, face)
  e.reserve(static_cast<size_t>(faces.rows()) * 3);
  for (int f = 0; f < faces.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      int i = faces(f, c), j = faces(f, (c + 1) % 3);
      e.push_back({std::min(i, j), std::max(i, j), f});
    }
  std::sort(e.begin(), e.end());
  std::vector<int> parent(static_cast<size_t>(faces.rows()));
  std::iota(parent.begin(), parent.end(), 0);
  for (size_t i = 0; i < e.size();) {
    size_t j = i;
    while (j < e.size() && e[j][0] == e[i][0] && e[j][1] == e[i][1]) ++j;
    ++s.edges;
    const size_t k = j - i;
    if (k == 1 || k > 2) {
      if (k == 1) ++s.open_edges; else ++s.nonmanifold_edges;
      if (s.first_bad_edge[0] < 0) { s.first_bad_edge[0] = e[i][0]; s.first_bad_edge[1] = e[i][1]; }
    }
    for (size_t q = i + 1; q < j; ++q) {
      int a = find_root(parent, e[i][2]), b = find_root(parent, e[q][2]);
      if (a != b) parent[static_cast<size_t>(a)] = b;
    }
    i = j;
  }
  for (int f = 0; f < faces.rows(); ++f)
    if (find_root(parent, f) == f) ++s.components;
  // vertex manifoldness: the faces around each vertex, joined through shared edges at that
  // vertex, must form one fan.
  std::vector<std::vector<int>> vf(static_cast<size_t>(num_vertices));
  for (int f = 0; f < faces.rows(); ++f)
    for (int c = 0; c < 3; ++c) vf[static_cast<size_t>(faces(f, c))].push_back(f);
  for (int v = 0; v < num_vertices; ++v) {
    const auto& fs = vf[static_cast<size_t>(v)];
    if (fs.empty()) continue;
    ++s.vertices;
    // union faces sharing an edge (v, w)
    std::unordered_map<int, int> first_face_of_w;
    std::vector<int> par(fs.size());
    std::iota(par.begin(), par.end(), 0);
    for (size_t a = 0; a < fs.size(); ++a)
      for (int c = 0; c < 3; ++c) {
        int w = faces(fs[a], c);
        if (w == v) continue;
        auto [it, inserted] = first_face_of_w.emplace(w, static_cast<int>(a));
        if (!inserted) {
          int x = find_root(par, it->second), y = find_root(par, static_cast<int>(a));
          if (x != y) par[static_cast<size_t>(x)] = y;
        }
      }
    int roots = 0;
    for (size_t a = 0; a < fs.size(); ++a)
      if (find_root(par, static_cast<int>(a)) == static_cast<int>(a)) ++roots;
    if (roots != 1) {
      ++s.nonmanifold_vertices;
      if (s.first_bad_vertex < 0) s.first_bad_vertex = v;
    }
  }
  s.euler = s.vertices - s.edges + s.faces;
  return s;
}

TriSurface boundary_surface(const TetMesh& mesh) {
  const Triangles faces = boundary_faces(mesh.tets);
  const std::vector<char> used = boundary_vertex_mask(mesh.num_vertices(), faces);
  std::vector<int> id(used.size(), -1);
  int n = 0;
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) id[v] = n++;
  TriSurface s;
  s.vertices.resize(n, 3);
  for (size_t v = 0; v < used.size(); ++v)
    if (used[v]) s.vertices.row(id[v]) = mesh.vertices.row(static_cast<Eigen::Index>(v));
  s.triangles.resize(faces.rows(), 3);
  for (Eigen::Index f = 0; f < faces.rows(); ++f)
    for (int c = 0; c < 3; ++c) s.triangles(f, c) = id[faces(f, c)];
  return s;
}

}  // namespace vpm
