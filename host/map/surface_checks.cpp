// The surface map's input checks and area metrics (vpm/surface_map.hpp), and the face areas
// they share with the map (map/surface_area.hpp).
#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Geometry>

#include "core/parallel.hpp"
#include "map/surface_area.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/surface_map.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace detail {

namespace {

Eigen::Vector3d row3(const Points& x, int i) { return x.row(i).transpose(); }

// Twice the signed area vector of face f: (b - a) x (c - a).
Eigen::Vector3d face_normal(const Points& x, const Triangles& f, int t) {
  const Eigen::Vector3d a = row3(x, f(t, 0));
  return (row3(x, f(t, 1)) - a).cross(row3(x, f(t, 2)) - a);
}

}  // namespace

Eigen::VectorXd face_areas(const Points& x, const Triangles& f) {
  Eigen::VectorXd a(f.rows());
  parallel_for(static_cast<int>(f.rows()), 16384, [&](int t0, int t1) {
    for (int t = t0; t < t1; ++t) a(t) = 0.5 * face_normal(x, f, t).norm();
  });
  return a;
}

std::vector<int> flipped_faces_in(SurfaceDomain domain, const Points& x, const Triangles& f) {
  std::vector<int> out;
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const Eigen::Vector3d a = row3(x, f(t, 0)), b = row3(x, f(t, 1)), c = row3(x, f(t, 2));
    const double s = domain == SurfaceDomain::sphere ? a.dot(b.cross(c)) : (b - a).cross(c - a)(2);
    if (s <= 0) out.push_back(static_cast<int>(t));
  }
  return out;
}

std::vector<int> boundary_loop(int n, const Triangles& f, const std::string& what) {
  // directed edges a -> b of the faces; an open edge is one whose reverse b -> a is in no face.
  // Walking the open edges in the faces' direction traces the loop with the faces on its left.
  std::vector<std::pair<int, int>> directed;
  directed.reserve(3 * static_cast<size_t>(f.rows()));
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) directed.emplace_back(f(t, k), f(t, (k + 1) % 3));
  std::sort(directed.begin(), directed.end());
  std::vector<int> next(static_cast<size_t>(n), -1);
  int open = 0, start = -1;
  for (const auto& [a, b] : directed)
    if (!std::binary_search(directed.begin(), directed.end(), std::make_pair(b, a))) {
      if (next[static_cast<size_t>(a)] >= 0)
        throw InputError(what + ": vertex " + std::to_string(a) + " is on the boundary twice: the surface pinches there");
      next[static_cast<size_t>(a)] = b;
      ++open;
      start = a;
    }
  std::vector<int> loop;
  if (open == 0) return loop;
  for (int v = start; loop.size() <= static_cast<size_t>(open);) {
    loop.push_back(v);
    v = next[static_cast<size_t>(v)];
    if (v < 0) throw InputError(what + ": the boundary is not a closed loop");
    if (v == start) break;
  }
  if (static_cast<int>(loop.size()) != open)
    throw InputError(what + ": " + std::to_string(open) + " open edges in more than one boundary loop; the disk map needs one");
  return loop;
}

std::vector<char> loop_mask(int n, const Triangles& f) {
  std::vector<char> mask(static_cast<size_t>(n), 0);
  for (int v : boundary_loop(n, f, "surface")) mask[static_cast<size_t>(v)] = 1;
  return mask;
}

}  // namespace detail

using detail::face_areas;

SurfaceMetrics surface_metrics(const Points& reference, const Points& mapped, const Triangles& faces,
                               SurfaceDomain domain) {
  if (reference.rows() != mapped.rows()) throw InputError("surface_metrics: reference and mapped differ in size");
  SurfaceMetrics m;
  const Eigen::VectorXd a0 = face_areas(reference, faces), a = face_areas(mapped, faces);
  const double s0 = a0.sum(), s = a.sum();
  m.face_ratio.resize(faces.rows());
  for (Eigen::Index t = 0; t < faces.rows(); ++t) m.face_ratio(t) = (a(t) / s) / (a0(t) / s0);
  Eigen::VectorXd d0 = Eigen::VectorXd::Zero(mapped.rows()), d = Eigen::VectorXd::Zero(mapped.rows());
  for (Eigen::Index t = 0; t < faces.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      d0(faces(t, k)) += a0(t) / 3;
      d(faces(t, k)) += a(t) / 3;
    }
  m.vertex_ratio = (d / s).cwiseQuotient(d0 / s0);
  m.face_area_ratio = ratio_stats(m.face_ratio);
  m.vertex_area_ratio = ratio_stats(m.vertex_ratio);
  m.flipped_faces = static_cast<int>(detail::flipped_faces_in(domain, mapped, faces).size());
  // the points that must be on the unit sphere or circle: all, or the disk's boundary
  const std::vector<char> on = domain == SurfaceDomain::sphere
                                   ? std::vector<char>(static_cast<size_t>(mapped.rows()), 1)
                                   : detail::loop_mask(static_cast<int>(mapped.rows()), faces);
  for (Eigen::Index i = 0; i < mapped.rows(); ++i)
    if (on[static_cast<size_t>(i)]) m.max_radius_error = std::max(m.max_radius_error, std::abs(mapped.row(i).norm() - 1.0));
  return m;
}

Json to_json(const SurfaceMetrics& m) {
  Json j = Json::object();
  j["flipped_faces"] = m.flipped_faces;
  j["face_area_ratio"] = to_json(m.face_area_ratio);
  j["vertex_area_ratio"] = to_json(m.vertex_area_ratio);
  j["max_radius_error"] = m.max_radius_error;
  return j;
}

namespace {

// The checks both domains share: indices, finite points, every vertex used, manifold edges and
// vertices (open edges refused when `closed`), one component, consistent orientation, no face
// without area. Returns the topology.
SurfaceTopology check_surface(const TriSurface& s, const std::string& what, bool closed) {
  const int n = static_cast<int>(s.vertices.rows());
  const Eigen::Index m = s.triangles.rows();
  if (m < (closed ? 4 : 1))
    throw InputError(what + ": " + std::to_string(m) + " triangles; the map needs at least " + (closed ? "4" : "1"));
  if (!s.vertices.allFinite()) throw InputError(what + ": a vertex coordinate is not finite");
  std::vector<char> used(static_cast<size_t>(n), 0);
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = s.triangles(t, k);
      if (v < 0 || v >= n)
        throw InputError(what + ": triangle " + std::to_string(t) + ": vertex index " + std::to_string(v) +
                         " out of range (" + std::to_string(n) + " vertices)");
      used[static_cast<size_t>(v)] = 1;
    }
  for (int v = 0; v < n; ++v)
    if (!used[static_cast<size_t>(v)])
      throw InputError(what + ": vertex " + std::to_string(v) + " is in no triangle; the map needs every vertex on the surface");
  const SurfaceTopology st = surface_topology(n, s.triangles);
  const std::string edge = "edge (" + std::to_string(st.first_bad_edge[0]) + ", " + std::to_string(st.first_bad_edge[1]) + ")";
  if (closed && st.open_edges)
    throw InputError(what + ": " + edge + " is open: the surface has holes (" + std::to_string(st.open_edges) +
                     " open edges); the sphere map needs a closed surface");
  if (st.nonmanifold_edges)
    throw InputError(what + ": " + edge + " has three or more triangles: not a manifold (" +
                     std::to_string(st.nonmanifold_edges) + " such edges)");
  if (st.nonmanifold_vertices)
    throw InputError(what + ": vertex " + std::to_string(st.first_bad_vertex) + ": the surface pinches there (" +
                     std::to_string(st.nonmanifold_vertices) + " non-manifold vertices)");
  if (st.components != 1)
    throw InputError(what + ": " + std::to_string(st.components) + " separate surfaces; the map needs exactly one");
  std::vector<std::pair<long long, long long>> directed;
  directed.reserve(3 * static_cast<size_t>(m));
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) directed.emplace_back(s.triangles(t, k), s.triangles(t, (k + 1) % 3));
  std::sort(directed.begin(), directed.end());
  for (size_t i = 1; i < directed.size(); ++i)
    if (directed[i] == directed[i - 1])
      throw InputError(what + ": edge (" + std::to_string(directed[i].first) + ", " + std::to_string(directed[i].second) +
                       ") runs the same way in two triangles: the faces are not consistently oriented");
  const Eigen::VectorXd a = face_areas(s.vertices, s.triangles);
  const double total = a.sum();
  for (Eigen::Index t = 0; t < m; ++t)
    if (!(a(t) > 1e-14 * total))
      throw InputError(what + ": triangle " + std::to_string(t) + " has no area (" + strprintf("%.3g", a(t)) +
                       "); face area ratios need every face to have one");
  return st;
}

}  // namespace

const char* to_string(SurfaceDomain d) { return d == SurfaceDomain::sphere ? "sphere" : "disk"; }

void validate_closed_surface(const TriSurface& s, const std::string& what) {
  const SurfaceTopology st = check_surface(s, what, true);
  if (st.euler != 2)
    throw InputError(what + ": Euler characteristic " + std::to_string(st.euler) + " (genus " + std::to_string(st.genus()) +
                     "); the sphere map needs a genus-0 surface (2)");
}

void validate_disk_surface(const TriSurface& s, const std::string& what) {
  const SurfaceTopology st = check_surface(s, what, false);
  if (st.open_edges == 0)
    throw InputError(what + ": the surface is closed; the disk map needs one boundary loop (map it to the sphere)");
  detail::boundary_loop(static_cast<int>(s.vertices.rows()), s.triangles, what);  // one loop, no pinch
  if (st.euler != 1)
    throw InputError(what + ": Euler characteristic " + std::to_string(st.euler) +
                     " with one boundary loop; the disk map needs a disk (1: no handles)");
}

SurfaceDomain surface_domain(const TriSurface& s) {
  const SurfaceTopology st = surface_topology(static_cast<int>(s.vertices.rows()), s.triangles);
  return st.open_edges == 0 ? SurfaceDomain::sphere : SurfaceDomain::disk;
}

}  // namespace vpm
