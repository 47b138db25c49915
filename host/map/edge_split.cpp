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

SplitResult split_boundary_edges(const TetMesh& input, int max_rounds) {
  SplitResult r;
  const int n0 = input.num_vertices();
  const Triangles bf = boundary_faces(input.tets);
  std::vector<char> bnd = boundary_vertex_mask(n0, bf);
  const auto bedges = surface_edges(bf);
  r.four_boundary_tets_before = count_four_boundary_tets(input.tets, bnd);

  std::vector<Eigen::Vector3d> X(n0);
  for (int i = 0; i < n0; ++i) X[i] = input.vertices.row(i).transpose();
  // sources[v]: vertices whose average v is (1, 2 or 4 of them)
  std::vector<std::vector<int>> sources(n0);
  for (int i = 0; i < n0; ++i) sources[i] = {i};
  std::vector<std::array<int, 4>> T(input.tets.rows());
  for (Eigen::Index i = 0; i < input.tets.rows(); ++i)
    for (int c = 0; c < 4; ++c) T[i][c] = input.tets(i, c);
  r.parent_tet.resize(T.size());
  std::iota(r.parent_tet.begin(), r.parent_tet.end(), 0);

  auto add_vertex = [&](const Eigen::Vector3d& p, std::vector<int> src) {
    X.push_back(p);
    sources.push_back(std::move(src));
    bnd.push_back(0);
    return static_cast<int>(X.size()) - 1;
  };

  for (int round = 0; round < max_rounds; ++round) {
    std::vector<std::pair<int, int>> cand;
    for (const auto& t : T)
      for (const auto& e : kEdges) {
        int a = t[e[0]], b = t[e[1]];
        if (!bnd[a] || !bnd[b]) continue;
        if (a > b) std::swap(a, b);
        if (!bedges.count({a, b})) cand.push_back({a, b});
      }
    std::sort(cand.begin(), cand.end());
    cand.erase(std::unique(cand.begin(), cand.end()), cand.end());
    if (cand.empty()) break;
    ++r.rounds;
    std::vector<std::vector<int>> inc(X.size());
    for (size_t i = 0; i < T.size(); ++i)
      for (int c = 0; c < 4; ++c) inc[T[i][c]].push_back(static_cast<int>(i));
    for (const auto& [a, b] : cand) {
      std::vector<int> around;
      for (int t : inc[a])
        if (T[t][0] == b || T[t][1] == b || T[t][2] == b || T[t][3] == b) around.push_back(t);
      if (around.empty()) continue;
      const int m = add_vertex(0.5 * (X[a] + X[b]), {a, b});
      inc.emplace_back();
      for (int t : around) {
        std::array<int, 4> child = T[t];
        for (int c = 0; c < 4; ++c) {
          if (T[t][c] == b) T[t][c] = m;   // (a, m, ...) stays in slot t
          if (child[c] == a) child[c] = m; // (m, b, ...) is new
        }
        const int tn = static_cast<int>(T.size());
        T.push_back(child);
        r.parent_tet.push_back(r.parent_tet[t]);
        auto& ib = inc[b];
        ib.erase(std::find(ib.begin(), ib.end(), t));
        for (int c = 0; c < 4; ++c)
          if (child[c] != m) inc[child[c]].push_back(tn);
        inc[m].push_back(t);
        inc[m].push_back(tn);
      }
    }
  }
  // Tets still with four boundary vertices have only boundary-surface edges: split 1 -> 4.
  const size_t nt = T.size();
  for (size_t t = 0; t < nt; ++t) {
    const auto q = T[t];
    if (!(bnd[q[0]] && bnd[q[1]] && bnd[q[2]] && bnd[q[3]])) continue;
    const int m = add_vertex(0.25 * (X[q[0]] + X[q[1]] + X[q[2]] + X[q[3]]), {q[0], q[1], q[2], q[3]});
    ++r.centroid_splits;
    for (int k = 0; k < 4; ++k) {
      std::array<int, 4> child = q;
      child[k] = m;
      if (k == 0) {
        T[t] = child;
      } else {
        T.push_back(child);
        r.parent_tet.push_back(r.parent_tet[t]);
      }
    }
  }

  const int n = static_cast<int>(X.size());
  r.inserted_vertices = n - n0;
  TetMesh& m = r.mesh;
  m.vertices.resize(n, 3);
  for (int i = 0; i < n; ++i) m.vertices.row(i) = X[i].transpose();
  m.tets.resize(static_cast<Eigen::Index>(T.size()), 4);
  for (size_t i = 0; i < T.size(); ++i)
    for (int c = 0; c < 4; ++c) m.tets(static_cast<Eigen::Index>(i), c) = T[i][c];
  r.parents.resize(n);
  for (int i = 0; i < n; ++i) {
    if (sources[i].size() == 1) r.parents[i] = {i, i};
    else if (sources[i].size() == 2) r.parents[i] = {sources[i][0], sources[i][1]};
    else r.parents[i] = {-1, -1};
  }
  // Carry fields.
  for (const Field& f : input.point_data) {
    if (f.name == "original_position") continue;
    FieldValues v(n, f.values.cols());
    v.topRows(n0) = f.values;
    for (int i = n0; i < n; ++i) {
      if (f.integer) {
        v.row(i) = v.row(sources[i][0]);
      } else {
        v.row(i).setZero();
        for (int s : sources[i]) v.row(i) += v.row(s);
        v.row(i) /= static_cast<double>(sources[i].size());
      }
    }
    m.set_point_field(f.name, std::move(v), f.integer);
  }
  for (const Field& f : input.cell_data) {
    FieldValues v(m.tets.rows(), f.values.cols());
    for (Eigen::Index i = 0; i < m.tets.rows(); ++i) v.row(i) = f.values.row(r.parent_tet[i]);
    m.set_cell_field(f.name, std::move(v), f.integer);
  }
  m.set_point_field("original_position", FieldValues(m.vertices));
  r.four_boundary_tets_after = count_four_boundary_tets(m.tets, bnd);
  return r;
}

}  // namespace vpm
