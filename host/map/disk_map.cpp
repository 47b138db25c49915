// The area-preserving map of a disk-like surface to the unit disk (vpm/surface_map.hpp): ears
// split, the boundary loop on the unit circle by arc length, the interior by Floater's mean value
// coordinates (fold-free: each interior vertex a convex combination of its neighbours, Tutte's
// theorem), then the polish of the face areas (map/surface_polish.hpp) in the plane.
#include <Eigen/Geometry>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>
#include <utility>
#include <vector>

#include "map/surface_area.hpp"
#include "map/surface_polish.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/surface_map.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace {

using Trip = Eigen::Triplet<double>;

// Mean value weights w_ij = (tan(a/2) + tan(b/2)) / |x_j - x_i|, a and b the angles at i of the
// two faces along edge ij: positive for every edge, whatever the faces' shapes.
std::vector<Trip> mean_value_weights(const Points& x, const Triangles& f) {
  std::vector<Trip> w;
  w.reserve(6 * static_cast<size_t>(f.rows()));
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int i = f(t, k), j = f(t, (k + 1) % 3), l = f(t, (k + 2) % 3);
      const Eigen::Vector3d a = (x.row(j) - x.row(i)).transpose(), b = (x.row(l) - x.row(i)).transpose();
      const double la = a.norm(), lb = b.norm();
      const double tan_half = (la * lb - a.dot(b)) / std::max(a.cross(b).norm(), 1e-300);  // (1 - cos) / sin
      w.emplace_back(i, j, tan_half / la);
      w.emplace_back(i, l, tan_half / lb);
    }
  return w;
}

// The boundary `loop` on the unit circle, counter-clockwise, at angles proportional to the arc
// length; the interior by mean value coordinates.
Points disk_embedding(const Points& x, const Triangles& f, const std::vector<int>& loop, const std::vector<char>& boundary) {
  const int n = static_cast<int>(x.rows());
  Points u = Points::Zero(n, 3);
  std::vector<double> arc(loop.size() + 1, 0.0);
  for (size_t k = 0; k < loop.size(); ++k)
    arc[k + 1] = arc[k] + (x.row(loop[(k + 1) % loop.size()]) - x.row(loop[k])).norm();
  for (size_t k = 0; k < loop.size(); ++k) {
    const double phi = 2 * M_PI * arc[k] / arc.back();
    u.row(loop[k]) << std::cos(phi), std::sin(phi), 0.0;
  }
  std::vector<int> unknown(static_cast<size_t>(n), -1);
  int m = 0;
  for (int v = 0; v < n; ++v)
    if (!boundary[static_cast<size_t>(v)]) unknown[static_cast<size_t>(v)] = m++;
  if (m == 0) return u;
  std::vector<Trip> a;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(m, 2);
  for (const Trip& w : mean_value_weights(x, f)) {
    const int i = unknown[static_cast<size_t>(w.row())];
    if (i < 0) continue;
    a.emplace_back(i, i, w.value());
    const int j = unknown[static_cast<size_t>(w.col())];
    if (j >= 0) a.emplace_back(i, j, -w.value());
    else rhs.row(i) += w.value() * u.row(w.col()).head<2>();
  }
  Eigen::SparseMatrix<double> A(m, m);
  A.setFromTriplets(a.begin(), a.end());
  Eigen::SparseLU<Eigen::SparseMatrix<double>> lu(A);
  if (lu.info() != Eigen::Success) throw NumericalError("map_to_disk: the mean value system could not be factored");
  const Eigen::MatrixXd sol = lu.solve(rhs);
  if (lu.info() != Eigen::Success || !sol.allFinite()) throw NumericalError("map_to_disk: the mean value system has no solution");
  for (int v = 0; v < n; ++v)
    if (const int i = unknown[static_cast<size_t>(v)]; i >= 0) u.row(v) << sol(i, 0), sol(i, 1), 0.0;
  return u;
}

// The ears (faces whose three corners are on the boundary loop) split: each ear's longest interior
// edge (one not on the loop) halved by a new vertex appended to `x`, the faces on a halved edge
// replaced by two (corner order, so orientation, kept). A new vertex is interior (its edge is), so
// no face left has three boundary corners, unless an ear has no interior edge (the surface is that
// one face). Returns the faces; `added` gets each new vertex's edge ends.
Triangles split_ears(Points& x, const Triangles& f, const std::vector<int>& loop, const std::vector<char>& on_loop,
                     std::vector<std::array<int, 2>>& added) {
  const int n = static_cast<int>(x.rows());
  auto key = [](int a, int b) { return std::make_pair(std::min(a, b), std::max(a, b)); };
  std::set<std::pair<int, int>> loop_edges;
  for (size_t k = 0; k < loop.size(); ++k) loop_edges.insert(key(loop[k], loop[(k + 1) % loop.size()]));
  std::map<std::pair<int, int>, int> mid;  // halved edge -> its new vertex
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    if (!(on_loop[static_cast<size_t>(f(t, 0))] && on_loop[static_cast<size_t>(f(t, 1))] &&
          on_loop[static_cast<size_t>(f(t, 2))]))
      continue;
    std::pair<int, int> best{-1, -1};
    double best_len = -1;
    for (int k = 0; k < 3; ++k) {
      const auto e = key(f(t, k), f(t, (k + 1) % 3));
      const double len = (x.row(e.first) - x.row(e.second)).squaredNorm();
      if (!loop_edges.count(e) && len > best_len) best = e, best_len = len;
    }
    if (best.first >= 0 && mid.emplace(best, n + static_cast<int>(added.size())).second)
      added.push_back({best.first, best.second});
  }
  if (added.empty()) return f;
  x.conservativeResize(n + static_cast<Eigen::Index>(added.size()), 3);
  for (size_t i = 0; i < added.size(); ++i)
    x.row(n + static_cast<Eigen::Index>(i)) = 0.5 * (x.row(added[i][0]) + x.row(added[i][1]));
  // a face is halved at its first halved edge, and its halves again where two ears chose two of
  // its edges (at most three levels)
  std::vector<Eigen::RowVector3i> out;
  std::function<void(int, int, int)> emit = [&](int a, int b, int c) {
    const int v[3] = {a, b, c};
    for (int k = 0; k < 3; ++k)
      if (const auto it = mid.find(key(v[k], v[(k + 1) % 3])); it != mid.end()) {
        emit(v[k], it->second, v[(k + 2) % 3]);
        emit(it->second, v[(k + 1) % 3], v[(k + 2) % 3]);
        return;
      }
    out.emplace_back(a, b, c);
  };
  for (Eigen::Index t = 0; t < f.rows(); ++t) emit(f(t, 0), f(t, 1), f(t, 2));
  Triangles g(static_cast<Eigen::Index>(out.size()), 3);
  for (size_t i = 0; i < out.size(); ++i) g.row(static_cast<Eigen::Index>(i)) = out[i];
  return g;
}

}  // namespace

FieldValues extend_to_mapped(const FieldValues& values, const SurfaceMapResult& result) {
  const Eigen::Index n = result.sphere.rows() - static_cast<Eigen::Index>(result.added.size());
  if (values.rows() != n)
    throw InputError("a per-vertex field has " + std::to_string(values.rows()) + " rows, the surface " +
                     std::to_string(n) + " vertices");
  FieldValues out(result.sphere.rows(), values.cols());
  out.topRows(n) = values;
  for (size_t i = 0; i < result.added.size(); ++i)
    out.row(n + static_cast<Eigen::Index>(i)) = 0.5 * (values.row(result.added[i][0]) + values.row(result.added[i][1]));
  return out;
}

const Triangles& mapped_faces(const Triangles& input_faces, const SurfaceMapResult& result) {
  return result.added.empty() ? input_faces : result.faces;
}

SurfaceMapResult map_to_disk(const TriSurface& input, const SurfaceMapOptions& opt) {
  const auto t_total = Clock::now();
  validate_disk_surface(input, "surface");
  SurfaceMapResult res;
  SurfaceMapReport& rep = res.report;
  rep.domain = SurfaceDomain::disk;
  rep.vertices = static_cast<int>(input.vertices.rows());
  rep.faces = static_cast<int>(input.triangles.rows());
  rep.tolerance = opt.tolerance;
  const int n_in = rep.vertices;
  const std::vector<int> loop = detail::boundary_loop(n_in, input.triangles, "surface");
  std::vector<char> on_loop(static_cast<size_t>(n_in), 0);
  for (int v : loop) on_loop[static_cast<size_t>(v)] = 1;
  rep.boundary_vertices = static_cast<int>(loop.size());
  for (Eigen::Index t = 0; t < input.triangles.rows(); ++t)
    if (on_loop[static_cast<size_t>(input.triangles(t, 0))] && on_loop[static_cast<size_t>(input.triangles(t, 1))] &&
        on_loop[static_cast<size_t>(input.triangles(t, 2))])
      ++rep.ears;
  // the surface mapped: the input, or with its ears split (new vertices interior, after the input's)
  Points reference = input.vertices;
  if (opt.split_ears && rep.ears > 0) res.faces = split_ears(reference, input.triangles, loop, on_loop, res.added);
  rep.split_edges = static_cast<int>(res.added.size());
  const Triangles& f = mapped_faces(input.triangles, res);
  const int n = static_cast<int>(reference.rows());
  detail::SurfaceDomainMoves domain{SurfaceDomain::disk, std::vector<char>(static_cast<size_t>(n), 0)};
  std::copy(on_loop.begin(), on_loop.end(), domain.boundary.begin());
  if (opt.progress && rep.split_edges > 0)
    opt.progress(
        strprintf("disk map: %d ears split (%d interior edges halved, a vertex each)", rep.ears, rep.split_edges));

  auto t0 = Clock::now();
  Points x = disk_embedding(reference, f, loop, domain.boundary);
  rep.seconds_sphere_map = seconds_since(t0);
  rep.initial = surface_metrics(reference, x, f, SurfaceDomain::disk);
  if (rep.initial.flipped_faces > 0)
    throw NumericalError("map_to_disk: the mean value embedding flipped " + std::to_string(rep.initial.flipped_faces) +
                         " faces (a boundary vertex whose faces are all on the circle?)");
  if (opt.progress)
    opt.progress(strprintf("disk embedding: face area mean |r-1| %.4f, %.2f s", rep.initial.face_area_ratio.mean_abs_dev,
                           rep.seconds_sphere_map));
  detail::polish_surface(domain, f, detail::face_areas(reference, f), opt, x, rep);
  res.sphere = std::move(x);
  rep.final = surface_metrics(reference, res.sphere, f, SurfaceDomain::disk);
  rep.converged = rep.final.face_area_ratio.mean_abs_dev <= opt.tolerance;
  rep.seconds_total = seconds_since(t_total);
  return res;
}

}  // namespace vpm
