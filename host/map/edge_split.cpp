// Step 1 of the initial map (vpm/initial_map.hpp): split interior edges whose ends are both on
// the boundary, so no tet has four boundary vertices (docs/design.md 4.1 step 1).
#include "vpm/initial_map.hpp"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <set>
#include <string>
#include <utility>

#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

constexpr int kEdges[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};

std::set<std::pair<int, int>> surface_edges(const Triangles& f) {
  std::set<std::pair<int, int>> e;
  for (Eigen::Index i = 0; i < f.rows(); ++i)
    for (int k = 0; k < 3; ++k) {
      int a = f(i, k), b = f(i, (k + 1) % 3);
      if (a > b) std::swap(a, b);
      e.insert({a, b});
    }
  return e;
}

}  // namespace

int count_four_boundary_tets(const Tets& tets, const std::vector<char>& boundary) {
  int c = 0;
  for (Eigen::Index i = 0; i < tets.rows(); ++i)
    if (boundary[tets(i, 0)] && boundary[tets(i, 1)] && boundary[tets(i, 2)] && boundary[tets(i, 3)]) ++c;
  return c;
}

namespace {

// The mesh being refined: positions, for each vertex the vertices it averages, tets, the input
// tet each tet lies in, and the boundary mask (inserted vertices are interior).
struct Refinement {
  std::vector<Eigen::Vector3d> X;
  int n0 = 0;                              // the input's vertices, each its own source
  std::vector<std::vector<int>> sources;  // per inserted vertex (n0 + i): the 2 or 4 it averages
  std::vector<std::array<int, 4>> T;
  std::vector<int> parent_tet;
  std::vector<char> bnd;
  int add_vertex(const Eigen::Vector3d& p, std::vector<int> src) {
    X.push_back(p);
    sources.push_back(std::move(src));
    bnd.push_back(0);
    return static_cast<int>(X.size()) - 1;
  }
};

Refinement start(const TetMesh& input, std::vector<char> bnd) {
  Refinement f;
  const int n0 = input.num_vertices();
  f.n0 = n0;
  f.X.resize(n0);
  for (int i = 0; i < n0; ++i) f.X[i] = input.vertices.row(i).transpose();
  f.T.resize(input.tets.rows());
  for (Eigen::Index i = 0; i < input.tets.rows(); ++i)
    for (int c = 0; c < 4; ++c) f.T[i][c] = input.tets(i, c);
  f.parent_tet.resize(f.T.size());
  std::iota(f.parent_tet.begin(), f.parent_tet.end(), 0);
  f.bnd = std::move(bnd);
  return f;
}

// Interior edges whose two ends are boundary vertices, sorted and unique.
std::vector<std::pair<int, int>> candidate_edges(const Refinement& f, const std::set<std::pair<int, int>>& bedges) {
  std::vector<std::pair<int, int>> cand;
  for (const auto& t : f.T)
    for (const auto& e : kEdges) {
      int a = t[e[0]], b = t[e[1]];
      if (!f.bnd[a] || !f.bnd[b]) continue;
      if (a > b) std::swap(a, b);
      if (!bedges.count({a, b})) cand.push_back({a, b});
    }
  std::sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  return cand;
}

// Splits every candidate edge at its midpoint: each tet around it becomes two. The tets around
// a vertex are kept only for the candidates' ends (the only ones asked), in the order a full
// incidence would list them.
void split_edges(Refinement& f, const std::vector<std::pair<int, int>>& cand) {
  auto& T = f.T;
  std::vector<char> tracked(f.X.size(), 0);
  for (const auto& [a, b] : cand) tracked[a] = tracked[b] = 1;
  std::vector<std::vector<int>> inc(f.X.size());
  for (size_t i = 0; i < T.size(); ++i)
    for (int c = 0; c < 4; ++c)
      if (tracked[T[i][c]]) inc[T[i][c]].push_back(static_cast<int>(i));
  for (const auto& [a, b] : cand) {
    std::vector<int> around;
    for (int t : inc[a])
      if (T[t][0] == b || T[t][1] == b || T[t][2] == b || T[t][3] == b) around.push_back(t);
    if (around.empty()) continue;
    const int m = f.add_vertex(0.5 * (f.X[a] + f.X[b]), {a, b});
    inc.emplace_back();
    tracked.push_back(0);
    for (int t : around) {
      std::array<int, 4> child = T[t];
      for (int c = 0; c < 4; ++c) {
        if (T[t][c] == b) T[t][c] = m;    // (a, m, ...) stays in slot t
        if (child[c] == a) child[c] = m;  // (m, b, ...) is new
      }
      const int tn = static_cast<int>(T.size());
      T.push_back(child);
      f.parent_tet.push_back(f.parent_tet[t]);
      auto& ib = inc[b];
      ib.erase(std::find(ib.begin(), ib.end(), t));
      for (int c = 0; c < 4; ++c)
        if (child[c] != m && tracked[child[c]]) inc[child[c]].push_back(tn);
    }
  }
}

// Tets still with four boundary vertices have only boundary-surface edges: split 1 -> 4 at the
// centroid. Returns the splits.
int split_centroids(Refinement& f) {
  int splits = 0;
  const size_t nt = f.T.size();
  for (size_t t = 0; t < nt; ++t) {
    const auto q = f.T[t];
    if (!(f.bnd[q[0]] && f.bnd[q[1]] && f.bnd[q[2]] && f.bnd[q[3]])) continue;
    const int m = f.add_vertex(0.25 * (f.X[q[0]] + f.X[q[1]] + f.X[q[2]] + f.X[q[3]]), {q[0], q[1], q[2], q[3]});
    ++splits;
    for (int k = 0; k < 4; ++k) {
      std::array<int, 4> child = q;
      child[k] = m;
      if (k == 0) {
        f.T[t] = child;
      } else {
        f.T.push_back(child);
        f.parent_tet.push_back(f.parent_tet[t]);
      }
    }
  }
  return splits;
}

// The refined mesh with the input's fields carried (point fields averaged over the sources,
// integer ones from the first; cell fields from the parent tet) and original_position.
void build_mesh(const Refinement& f, const TetMesh& input, SplitResult& r) {
  const int n0 = input.num_vertices(), n = static_cast<int>(f.X.size());
  TetMesh& m = r.mesh;
  m.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) m.vertices.row(i) = f.X[i].transpose();
  m.tets.resize(static_cast<Eigen::Index>(f.T.size()), 4);
  for (size_t i = 0; i < f.T.size(); ++i)
    for (int c = 0; c < 4; ++c) m.tets(static_cast<Eigen::Index>(i), c) = f.T[i][c];
  r.parents.resize(n);
  for (int i = 0; i < n; ++i) {
    if (i < n0) {
      r.parents[i] = {i, i};
      continue;
    }
    const auto& s = f.sources[static_cast<size_t>(i - n0)];
    r.parents[i] = s.size() == 2 ? std::array<int, 2>{s[0], s[1]} : std::array<int, 2>{-1, -1};
  }
  for (const Field& fd : input.point_data) {
    if (fd.name == "original_position") continue;
    FieldValues v(n, fd.values.cols());
    v.topRows(n0) = fd.values;
    for (int i = n0; i < n; ++i) {
      const auto& src = f.sources[static_cast<size_t>(i - n0)];
      if (fd.integer) {
        v.row(i) = v.row(src[0]);
      } else {
        v.row(i).setZero();
        for (int s : src) v.row(i) += v.row(s);
        v.row(i) /= static_cast<double>(src.size());
      }
    }
    m.set_point_field(fd.name, std::move(v), fd.integer);
  }
  for (const Field& fd : input.cell_data) {
    FieldValues v(m.tets.rows(), fd.values.cols());
    for (Eigen::Index i = 0; i < m.tets.rows(); ++i) v.row(i) = fd.values.row(f.parent_tet[i]);
    m.set_cell_field(fd.name, std::move(v), fd.integer);
  }
  m.set_point_field("original_position", FieldValues(m.vertices));
}

}  // namespace

SplitResult split_boundary_edges(const TetMesh& input, int max_rounds) {
  return split_boundary_edges(input, boundary_faces(input.tets), max_rounds);
}

SplitResult split_boundary_edges(const TetMesh& input, const Triangles& bf, int max_rounds) {
  SplitResult r;
  std::vector<char> bnd = boundary_vertex_mask(input.num_vertices(), bf);
  const auto bedges = surface_edges(bf);
  r.four_boundary_tets_before = count_four_boundary_tets(input.tets, bnd);
  Refinement f = start(input, std::move(bnd));
  for (int round = 0; round < max_rounds; ++round) {
    const auto cand = candidate_edges(f, bedges);
    if (cand.empty()) break;
    ++r.rounds;
    split_edges(f, cand);
  }
  r.centroid_splits = split_centroids(f);
  r.inserted_vertices = static_cast<int>(f.X.size()) - input.num_vertices();
  r.parent_tet = f.parent_tet;
  build_mesh(f, input, r);
  r.four_boundary_tets_after = count_four_boundary_tets(r.mesh.tets, f.bnd);
  r.boundary = bf;
  return r;
}

SplitResult split_edges_near(const TetMesh& mesh, const Triangles& bf, const std::vector<int>& seed_tets,
                             int rings) {
  SplitResult r;
  const int n = mesh.num_vertices();
  std::vector<char> bnd = boundary_vertex_mask(n, bf);
  const auto bedges = surface_edges(bf);
  // the tets within `rings` vertex rings of the seeds: those with all four vertices near them
  const std::vector<char> near = vertices_near_tets(n, mesh.tets, seed_tets, rings);
  std::vector<std::pair<int, int>> cand;
  for (int t = 0; t < mesh.num_tets(); ++t) {
    bool inside = true;
    for (int c = 0; c < 4; ++c) inside = inside && near[static_cast<size_t>(mesh.tets(t, c))];
    if (!inside) continue;
    for (const auto& e : kEdges) {
      int a = mesh.tets(t, e[0]), b = mesh.tets(t, e[1]);
      if (a > b) std::swap(a, b);
      if (!bedges.count({a, b})) cand.push_back({a, b});
    }
  }
  std::sort(cand.begin(), cand.end());
  cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
  Refinement f = start(mesh, std::move(bnd));
  r.rounds = 1;
  split_edges(f, cand);
  r.inserted_vertices = static_cast<int>(f.X.size()) - n;
  r.parent_tet = f.parent_tet;
  build_mesh(f, mesh, r);
  r.four_boundary_tets_before = r.four_boundary_tets_after = count_four_boundary_tets(r.mesh.tets, f.bnd);
  r.boundary = bf;
  return r;
}

}  // namespace vpm
