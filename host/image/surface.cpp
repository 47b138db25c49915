// Surfaces of the image layer (see surface.hpp) and the public surface helpers of
// vpm/mesh_image.hpp: triangle angles, and the remeshing stand-in of a build without CGAL.
#include "image/surface.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <unordered_map>

#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/topology.hpp"

namespace vpm {
namespace detail {

namespace {

// The six Kuhn tets of a cube as corner bit masks, positively oriented.
struct KuhnTets {
  int tet[6][4];
  KuhnTets() {
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int p = 0; p < 6; ++p) {
      const int a0 = perms[p][0], a1 = perms[p][1], a2 = perms[p][2];
      int v1 = 1 << a0, v2 = v1 | (1 << a1);
      tet[p][0] = 0, tet[p][1] = v1, tet[p][2] = v2, tet[p][3] = 7;
      // orientation = sign of the permutation (a0 a1 a2)
      const int inv = (a0 > a1) + (a0 > a2) + (a1 > a2);
      if (inv % 2) std::swap(tet[p][2], tet[p][3]);
    }
  }
};

std::array<int, 3> corner(int b) { return std::array<int, 3>{b & 1, (b >> 1) & 1, (b >> 2) & 1}; }

// Marching tetrahedra state: the vertices made so far (one per crossed grid edge) and the
// triangles.
class MarchingTets {
 public:
  MarchingTets(const Grid3& g, const std::vector<float>& f, float iso) : g_(g), f_(f), iso_(iso) {
    edge_vertex_.reserve(1 << 16);
  }

  // Triangulates the crossing of every cube that has corners on both sides.
  void run() {
    for (int z = 0; z + 1 < g_.nz; ++z)
      for (int y = 0; y + 1 < g_.ny; ++y)
        for (int x = 0; x + 1 < g_.nx; ++x) cube(x, y, z);
  }

  TriSurface surface() const {
    TriSurface s;
    s.vertices.resize(Eigen::Index(pts_.size()), 3);
    for (size_t i = 0; i < pts_.size(); ++i) s.vertices.row(Eigen::Index(i)) = pts_[i].transpose();
    s.triangles.resize(Eigen::Index(tris_.size()), 3);
    for (size_t i = 0; i < tris_.size(); ++i)
      for (int c = 0; c < 3; ++c) s.triangles(Eigen::Index(i), c) = tris_[i][c];
    return s;
  }

 private:
  // The vertex on grid edge p-q (positions pp, pq), made on first use.
  int vertex_on(uint64_t p, uint64_t q, const Eigen::Vector3d& pp, const Eigen::Vector3d& pq) {
    const uint64_t key = std::min(p, q) * uint64_t(g_.size()) + std::max(p, q);
    auto it = edge_vertex_.find(key);
    if (it != edge_vertex_.end()) return it->second;
    double t = (double(iso_) - f_[p]) / (double(f_[q]) - f_[p]);
    t = std::clamp(t, 0.02, 0.98);
    pts_.push_back(pp + t * (pq - pp));
    const int id = int(pts_.size()) - 1;
    edge_vertex_.emplace(key, id);
    return id;
  }

  void cube(int x, int y, int z) {
    uint64_t id[8];
    bool in[8];
    int nin = 0;
    for (int b = 0; b < 8; ++b) {
      const auto c = corner(b);
      id[b] = g_.idx(x + c[0], y + c[1], z + c[2]);
      in[b] = f_[id[b]] > iso_;
      nin += in[b];
    }
    if (nin == 0 || nin == 8) return;
    for (int t = 0; t < 6; ++t) tet(x, y, z, kuhn_.tet[t], id, in);
  }

  // One Kuhn tet (corner masks vi) of cube (x, y, z): one triangle or a quad split in two.
  void tet(int x, int y, int z, const int (&vi)[4], const uint64_t (&id)[8], const bool (&in)[8]) {
    int nin_t = 0;
    Eigen::Vector3d P[4];
    for (int k = 0; k < 4; ++k) {
      const auto c = corner(vi[k]);
      P[k] = Eigen::Vector3d(x + c[0], y + c[1], z + c[2]);
      nin_t += in[vi[k]];
    }
    if (nin_t == 0 || nin_t == 4) return;
    std::vector<int> ins, outs;
    for (int k = 0; k < 4; ++k) (in[vi[k]] ? ins : outs).push_back(k);
    auto V = [&](int a, int b) { return vertex_on(id[vi[a]], id[vi[b]], P[a], P[b]); };
    auto det = [&](int a, int b, int c, int d) { return (P[b] - P[a]).dot((P[c] - P[a]).cross(P[d] - P[a])); };
    if (ins.size() == 1) {
      const int a = ins[0], b = outs[0], c = outs[1], d = outs[2];
      std::array<int, 3> tri{V(a, b), V(a, c), V(a, d)};
      if (det(a, b, c, d) < 0) std::swap(tri[1], tri[2]);
      tris_.push_back(tri);
    } else if (ins.size() == 3) {
      const int d = outs[0], a = ins[0], b = ins[1], c = ins[2];
      std::array<int, 3> tri{V(a, d), V(b, d), V(c, d)};
      if (det(d, a, b, c) > 0) std::swap(tri[1], tri[2]);
      tris_.push_back(tri);
    } else {
      const int a = ins[0], b = ins[1], c = outs[0], d = outs[1];
      const int q[4] = {V(a, c), V(a, d), V(b, d), V(b, c)};
      // Newell normal of the quad vs the in -> out direction
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k) n += pts_[q[k]].cross(pts_[q[(k + 1) % 4]]);
      const Eigen::Vector3d dir = P[c] + P[d] - P[a] - P[b];
      if (n.dot(dir) >= 0) {
        tris_.push_back({q[0], q[1], q[2]});
        tris_.push_back({q[0], q[2], q[3]});
      } else {
        tris_.push_back({q[0], q[2], q[1]});
        tris_.push_back({q[0], q[3], q[2]});
      }
    }
  }

  const Grid3& g_;
  const std::vector<float>& f_;
  const float iso_;
  const KuhnTets kuhn_;
  std::vector<Eigen::Vector3d> pts_;
  std::vector<std::array<int, 3>> tris_;
  std::unordered_map<uint64_t, int> edge_vertex_;
};

}  // namespace

TriSurface marching_tets(const Grid3& g, const std::vector<float>& f, float iso) {
  MarchingTets m(g, f, iso);
  m.run();
  return m.surface();
}

double mean_edge(const TriSurface& s) {
  double sum = 0;
  for (int f = 0; f < s.triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      sum += (s.vertices.row(s.triangles(f, c)) - s.vertices.row(s.triangles(f, (c + 1) % 3))).norm();
  return s.triangles.rows() ? sum / (3.0 * s.triangles.rows()) : 0;
}

double enclosed_volume(const TriSurface& s) {
  double v = 0;
  for (int f = 0; f < s.triangles.rows(); ++f) {
    const Eigen::Vector3d a = s.vertices.row(s.triangles(f, 0)), b = s.vertices.row(s.triangles(f, 1)),
                          c = s.vertices.row(s.triangles(f, 2));
    v += a.dot(b.cross(c)) / 6;
  }
  return v;
}

SurfaceStats surface_stats(const TriSurface& s) {
  SurfaceStats j;
  const auto topo = surface_topology(int(s.vertices.rows()), s.triangles);
  const auto ang = triangle_angle_range_deg(s);
  j.vertices = int(s.vertices.rows());
  j.triangles = int(s.triangles.rows());
  j.euler = topo.euler;
  j.mean_edge_mm = mean_edge(s);
  j.min_angle_deg = ang.first;
  j.max_angle_deg = ang.second;
  return j;
}

void check_closed_genus0(const TriSurface& s, const std::string& source, const std::string& what) {
  const auto t = surface_topology(int(s.vertices.rows()), s.triangles);
  std::string why;
  if (t.open_edges) why = std::to_string(t.open_edges) + " open edges (e.g. " + std::to_string(t.first_bad_edge[0]) + "-" + std::to_string(t.first_bad_edge[1]) + ")";
  else if (t.nonmanifold_edges) why = std::to_string(t.nonmanifold_edges) + " non-manifold edges";
  else if (t.nonmanifold_vertices) why = std::to_string(t.nonmanifold_vertices) + " non-manifold vertices (e.g. vertex " + std::to_string(t.first_bad_vertex) + ")";
  else if (t.components != 1) why = std::to_string(t.components) + " connected components";
  else if (t.euler != 2) why = "genus " + std::to_string(t.genus()) + " (Euler characteristic " + std::to_string(t.euler) + ")";
  if (!why.empty()) throw InputError(source + ": " + what + " is not a closed genus-0 surface: " + why);
}

}  // namespace detail

std::pair<double, double> triangle_angle_range_deg(const TriSurface& s) {
  double lo = 180, hi = 0;
  for (int f = 0; f < s.triangles.rows(); ++f) {
    Eigen::Vector3d p[3];
    for (int c = 0; c < 3; ++c) p[c] = s.vertices.row(s.triangles(f, c));
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d u = p[(c + 1) % 3] - p[c], v = p[(c + 2) % 3] - p[c];
      const double a = std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / M_PI;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
  }
  return {lo, hi};
}

#if !VPM_HAVE_CGAL
TriSurface remesh_surface(const TriSurface&, double, int, RemeshInfo*) {
  throw InputError("mesh-image: this vpm was built without CGAL (surface remeshing unavailable)");
}
#endif

}  // namespace vpm
