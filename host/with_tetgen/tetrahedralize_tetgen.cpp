// Tetrahedralisation of a closed surface with TetGen 1.5 (AGPL-3+), linked as a library.
// The only translation unit that includes TetGen.
#include <tetgen.h>

#include <Eigen/Dense>
#include <cmath>
#include <csignal>
#include <cstring>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <set>
#include <vector>

#include "core/child_process.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

std::string tetgen_error(int code) {
  switch (code) {
    case 1: return "out of memory";
    case 2: return "internal error";
    case 3: return "the surface self-intersects";
    case 4: return "a very small input feature (points or edges too close)";
    case 5: return "two very close input facets";
    case 10: return "invalid input";
    default: return "error code " + std::to_string(code);
  }
}

void run_tetgen_here(const std::string& switches, const TriSurface& s, const std::vector<Eigen::Vector3d>& extra,
                     TetMesh& mesh) {
  tetgenio in, add, out;
  in.firstnumber = 0;
  in.numberofpoints = int(s.vertices.rows());
  in.pointlist = new REAL[3 * in.numberofpoints];
  for (int i = 0; i < in.numberofpoints; ++i)
    for (int d = 0; d < 3; ++d) in.pointlist[3 * i + d] = s.vertices(i, d);
  in.numberoffacets = int(s.triangles.rows());
  in.facetlist = new tetgenio::facet[in.numberoffacets];
  for (int f = 0; f < in.numberoffacets; ++f) {
    tetgenio::facet& fc = in.facetlist[f];
    tetgenio::init(&fc);
    fc.numberofpolygons = 1;
    fc.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&fc.polygonlist[0]);
    fc.polygonlist[0].numberofvertices = 3;
    fc.polygonlist[0].vertexlist = new int[3];
    for (int c = 0; c < 3; ++c) fc.polygonlist[0].vertexlist[c] = s.triangles(f, c);
  }
  std::string sw = switches;
  if (!extra.empty()) {
    add.firstnumber = 0;
    add.numberofpoints = int(extra.size());
    add.pointlist = new REAL[3 * extra.size()];
    for (size_t i = 0; i < extra.size(); ++i)
      for (int d = 0; d < 3; ++d) add.pointlist[3 * i + d] = extra[i][d];
    sw += "i";
  }
  std::vector<char> buf(sw.begin(), sw.end());
  buf.push_back('\0');
  try {
    tetrahedralize(buf.data(), &in, &out, extra.empty() ? nullptr : &add, nullptr);
  } catch (int code) {
    const std::string what = "TetGen (-" + sw + ") failed: " + tetgen_error(code);
    if (code == 1 || code == 2) throw NumericalError(what);
    throw InputError(what);  // the surface itself: self-intersecting, too-close features, invalid
  }
  if (out.numberoftetrahedra <= 0 || out.numberofcorners < 4)
    throw NumericalError("TetGen (-" + sw + ") produced no tetrahedra");
  mesh = TetMesh();
  mesh.vertices.resize(out.numberofpoints, 3);
  for (int i = 0; i < out.numberofpoints; ++i)
    for (int d = 0; d < 3; ++d) mesh.vertices(i, d) = out.pointlist[3 * i + d];
  mesh.tets.resize(out.numberoftetrahedra, 4);
  const int base = out.firstnumber;
  for (int t = 0; t < out.numberoftetrahedra; ++t)
    for (int c = 0; c < 4; ++c) mesh.tets(t, c) = out.tetrahedronlist[t * out.numberofcorners + c] - base;
  // Positive orientation (signed volume > 0).
  for (int t = 0; t < mesh.num_tets(); ++t) {
    const Eigen::Vector3d a = mesh.vertices.row(mesh.tets(t, 0));
    const Eigen::Vector3d b = mesh.vertices.row(mesh.tets(t, 1));
    const Eigen::Vector3d c = mesh.vertices.row(mesh.tets(t, 2));
    const Eigen::Vector3d d = mesh.vertices.row(mesh.tets(t, 3));
    if ((b - a).dot((c - a).cross(d - a)) < 0) std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
  }
}

// TetGen runs in a child process (core/child_process.hpp): its error paths have crashed in its
// own memory clean-up (tetgenmesh::freememory) after rejecting a surface, and a crash must not
// take vpm down. VPM_TEST_TETGEN_CRASH=1 makes the child crash on purpose (tests of this path).
void run_tetgen(const std::string& switches, const TriSurface& s, const std::vector<Eigen::Vector3d>& extra,
                TetMesh& mesh) {
  const std::string bytes = detail::run_in_child(
      [&] {
        if (const char* crash = std::getenv("VPM_TEST_TETGEN_CRASH"); crash && std::string(crash) == "1")
          std::raise(SIGSEGV);
        TetMesh m;
        run_tetgen_here(switches, s, extra, m);
        const int counts[2] = {m.num_vertices(), m.num_tets()};
        std::string out(reinterpret_cast<const char*>(counts), sizeof counts);
        out.append(reinterpret_cast<const char*>(m.vertices.data()), sizeof(double) * m.vertices.size());
        out.append(reinterpret_cast<const char*>(m.tets.data()), sizeof(int) * m.tets.size());
        return out;
      },
      "TetGen (-" + switches + ")", " on this surface: it usually means self-intersecting or nearly touching parts");
  int counts[2] = {0, 0};
  if (bytes.size() >= sizeof counts) std::memcpy(counts, bytes.data(), sizeof counts);
  mesh = TetMesh();
  mesh.vertices.resize(counts[0], 3);
  mesh.tets.resize(counts[1], 4);
  const size_t nv = sizeof(double) * mesh.vertices.size();
  if (bytes.size() != sizeof counts + nv + sizeof(int) * mesh.tets.size())
    throw NumericalError("TetGen (-" + switches + "): the mesh from the child process is truncated");
  std::memcpy(mesh.vertices.data(), bytes.data() + sizeof counts, nv);
  std::memcpy(mesh.tets.data(), bytes.data() + sizeof counts + nv, sizeof(int) * mesh.tets.size());
}

// Removes vertices no tet uses (TetGen keeps none normally, but -i may leave some).
void drop_unused_vertices(TetMesh& m) {
  std::vector<int> map(m.num_vertices(), -1);
  for (int t = 0; t < m.num_tets(); ++t)
    for (int c = 0; c < 4; ++c) map[m.tets(t, c)] = 0;
  int n = 0;
  for (auto& v : map)
    if (v == 0) v = n++;
  if (n == m.num_vertices()) return;
  Points p(n, 3);
  for (int i = 0; i < m.num_vertices(); ++i)
    if (map[i] >= 0) p.row(map[i]) = m.vertices.row(i);
  m.vertices = p;
  for (int t = 0; t < m.num_tets(); ++t)
    for (int c = 0; c < 4; ++c) m.tets(t, c) = map[m.tets(t, c)];
}

// Smallest dihedral angle (degrees) of tet (a, b, c, d); negative volume gives -1.
double tet_min_dihedral(const Eigen::Vector3d* p) {
  if ((p[1] - p[0]).dot((p[2] - p[0]).cross(p[3] - p[0])) <= 0) return -1;
  const int e[6][4] = {{0, 1, 2, 3}, {0, 2, 1, 3}, {0, 3, 1, 2}, {1, 2, 0, 3}, {1, 3, 0, 2}, {2, 3, 0, 1}};
  double lo = 180;
  for (auto& q : e) {
    const Eigen::Vector3d ax = (p[q[1]] - p[q[0]]).normalized();
    Eigen::Vector3d u = p[q[2]] - p[q[0]], v = p[q[3]] - p[q[0]];
    u -= ax * ax.dot(u);
    v -= ax * ax.dot(v);
    lo = std::min(lo, std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / M_PI);
  }
  return lo;
}

// Moves each vertex >= first (interior vertices inserted by splits) to the position among
// blends of its current place and the centroid of its neighbours that maximises the smallest
// dihedral angle of its tets (all kept positive).
void optimise_inserted_vertices(TetMesh& mesh, int first) {
  const int n = mesh.num_vertices();
  if (first >= n) return;
  std::vector<std::vector<int>> tets_of(n - first);
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int c = 0; c < 4; ++c)
      if (mesh.tets(t, c) >= first) tets_of[mesh.tets(t, c) - first].push_back(t);
  auto worst = [&](int v) {
    double lo = 180;
    for (int t : tets_of[v - first]) {
      Eigen::Vector3d p[4];
      for (int c = 0; c < 4; ++c) p[c] = mesh.vertices.row(mesh.tets(t, c));
      lo = std::min(lo, tet_min_dihedral(p));
    }
    return lo;
  };
  for (int pass = 0; pass < 4; ++pass)
    for (int v = first; v < n; ++v) {
      const auto& ts = tets_of[v - first];
      if (ts.empty()) continue;
      Eigen::Vector3d centre = Eigen::Vector3d::Zero();
      int k = 0;
      for (int t : ts)
        for (int c = 0; c < 4; ++c)
          if (mesh.tets(t, c) != v) centre += mesh.vertices.row(mesh.tets(t, c)).transpose(), ++k;
      centre /= k;
      const Eigen::Vector3d start = mesh.vertices.row(v).transpose();
      Eigen::Vector3d best = start;
      double best_q = worst(v);
      for (double w : {0.2, 0.4, 0.6, 0.8, 1.0}) {
        mesh.vertices.row(v) = ((1 - w) * start + w * centre).transpose();
        const double q = worst(v);
        if (q > best_q) best_q = q, best = mesh.vertices.row(v).transpose();
      }
      mesh.vertices.row(v) = best.transpose();
    }
}

// Splits, for every tet whose four vertices are on the boundary, its longest edge that is not
// a boundary edge (both ends on the boundary, interior segment). Returns the number of splits.
int split_four_boundary_vertex_tets(TetMesh& mesh, int* centroid_splits) {
  const Triangles bf = boundary_faces(mesh.tets);
  const auto on_b = boundary_vertex_mask(mesh.num_vertices(), bf);
  std::set<std::pair<int, int>> bedges;
  for (int f = 0; f < bf.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      int a = bf(f, c), b = bf(f, (c + 1) % 3);
      bedges.insert({std::min(a, b), std::max(a, b)});
    }
  std::set<std::pair<int, int>> to_split;
  std::vector<int> lone;
  const int pairs[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};
  for (int t = 0; t < mesh.num_tets(); ++t) {
    if (!(on_b[mesh.tets(t, 0)] && on_b[mesh.tets(t, 1)] && on_b[mesh.tets(t, 2)] && on_b[mesh.tets(t, 3)])) continue;
    double best = -1;
    std::pair<int, int> e{-1, -1};
    for (auto& p : pairs) {
      int a = mesh.tets(t, p[0]), b = mesh.tets(t, p[1]);
      if (a > b) std::swap(a, b);
      if (bedges.count({a, b})) continue;
      const double len = (mesh.vertices.row(a) - mesh.vertices.row(b)).norm();
      if (len > best) best = len, e = {a, b};
    }
    if (e.first >= 0) {
      to_split.insert(e);
    } else {
      lone.push_back(t);  // all six edges on the surface: split the tet at its centroid (1 -> 4)
    }
  }
  for (int t : lone) {
    const int m = mesh.num_vertices();
    mesh.vertices.conservativeResize(m + 1, 3);
    mesh.vertices.row(m).setZero();
    for (int k = 0; k < 4; ++k) mesh.vertices.row(m) += 0.25 * mesh.vertices.row(mesh.tets(t, k));
    const Eigen::RowVector4i v = mesh.tets.row(t);
    const int old = mesh.num_tets();
    mesh.tets.conservativeResize(old + 3, 4);
    for (int k = 1; k < 4; ++k) {
      Eigen::RowVector4i w = v;
      w(k) = m;
      mesh.tets.row(old + k - 1) = w;
    }
    mesh.tets(t, 0) = m;
    if (centroid_splits) ++*centroid_splits;
  }
  int n = 0;
  for (const auto& [a, b] : to_split) {
    std::vector<int> around;
    for (int t = 0; t < mesh.num_tets(); ++t) {
      bool ha = false, hb = false;
      for (int c = 0; c < 4; ++c) ha |= mesh.tets(t, c) == a, hb |= mesh.tets(t, c) == b;
      if (ha && hb) around.push_back(t);
    }
    if (around.empty()) continue;
    const int m = mesh.num_vertices();
    mesh.vertices.conservativeResize(m + 1, 3);
    mesh.vertices.row(m) = 0.5 * (mesh.vertices.row(a) + mesh.vertices.row(b));
    const int old = mesh.num_tets();
    mesh.tets.conservativeResize(old + Eigen::Index(around.size()), 4);
    for (size_t k = 0; k < around.size(); ++k) {
      const int t = around[k];
      Eigen::RowVector4i copy = mesh.tets.row(t);
      for (int c = 0; c < 4; ++c) {
        if (mesh.tets(t, c) == b) mesh.tets(t, c) = m;  // (a, m) half keeps the orientation
        if (copy(c) == a) copy(c) = m;                  // (m, b) half
      }
      mesh.tets.row(old + Eigen::Index(k)) = copy;
    }
    ++n;
  }
  return n + int(lone.size());
}

}  // namespace

TetMesh tetrahedralize_surface(const TriSurface& surface, const TetgenOptions& options, TetgenInfo* info) {
  char num[64];
  std::string sw = "pq";
  std::snprintf(num, sizeof num, "%g/%g", options.radius_edge, options.min_dihedral_deg);
  sw += num;
  if (options.max_volume > 0) {
    std::snprintf(num, sizeof num, "a%.6g", options.max_volume);
    sw += num;
  }
  if (options.preserve_surface) sw += "Y";
  sw += "zQ";
  TetMesh mesh;
  std::vector<Eigen::Vector3d> extra;
  run_tetgen(sw, surface, extra, mesh);
  int rounds = 0, bad = count_four_boundary_vertex_tets(mesh);
  while (bad > 0 && rounds < options.fix_rounds) {
    // Insert the centroid of every tet with four boundary vertices and mesh again: the
    // Delaunay cavity of an interior point contains that tet, and every new tet has the
    // point as a vertex.
    const Triangles bf = boundary_faces(mesh.tets);
    const auto on_b = boundary_vertex_mask(mesh.num_vertices(), bf);
    for (int t = 0; t < mesh.num_tets(); ++t) {
      if (on_b[mesh.tets(t, 0)] && on_b[mesh.tets(t, 1)] && on_b[mesh.tets(t, 2)] && on_b[mesh.tets(t, 3)]) {
        Eigen::Vector3d c = Eigen::Vector3d::Zero();
        for (int k = 0; k < 4; ++k) c += mesh.vertices.row(mesh.tets(t, k)).transpose();
        extra.push_back(c / 4);
      }
    }
    ++rounds;
    run_tetgen(sw, surface, extra, mesh);
    bad = count_four_boundary_vertex_tets(mesh);
  }
  drop_unused_vertices(mesh);
  // What point insertion left: split the longest interior edge of each remaining such tet
  // at its midpoint (docs/design.md 4.1 step 1); the new vertex is interior.
  int splits = 0, centroids = 0;
  const int first_inserted = mesh.num_vertices();
  for (int guard = 0; bad > 0 && guard < 8; ++guard) {
    splits += split_four_boundary_vertex_tets(mesh, &centroids);
    bad = count_four_boundary_vertex_tets(mesh);
  }
  optimise_inserted_vertices(mesh, first_inserted);
  if (info) {
    info->edge_splits = splits;
    info->switches = sw;
    info->fix_rounds = rounds;
    info->interior_points_added = int(extra.size());
    info->four_boundary_vertex_tets = bad;
  }
  return mesh;
}

}  // namespace vpm
