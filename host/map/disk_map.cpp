// The area-preserving map of a disk-like surface to the unit disk (vpm/surface_map.hpp): the
// boundary loop on the unit circle by arc length, the interior by Floater's mean value
// coordinates (fold-free: each interior vertex a convex combination of its neighbours, Tutte's
// theorem), then the polish of the face areas (map/surface_polish.hpp) in the plane.
#include <Eigen/Geometry>
#include <Eigen/SparseLU>
#include <cmath>
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

}  // namespace

SurfaceMapResult map_to_disk(const TriSurface& input, const SurfaceMapOptions& opt) {
  const auto t_total = Clock::now();
  validate_disk_surface(input, "surface");
  SurfaceMapResult res;
  SurfaceMapReport& rep = res.report;
  rep.domain = SurfaceDomain::disk;
  rep.vertices = static_cast<int>(input.vertices.rows());
  rep.faces = static_cast<int>(input.triangles.rows());
  rep.tolerance = opt.tolerance;
  const Triangles& f = input.triangles;
  const int n = rep.vertices;
  const std::vector<int> loop = detail::boundary_loop(n, f, "surface");
  detail::SurfaceDomainMoves domain{SurfaceDomain::disk, std::vector<char>(static_cast<size_t>(n), 0)};
  for (int v : loop) domain.boundary[static_cast<size_t>(v)] = 1;
  rep.boundary_vertices = static_cast<int>(loop.size());
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    if (domain.boundary[static_cast<size_t>(f(t, 0))] && domain.boundary[static_cast<size_t>(f(t, 1))] &&
        domain.boundary[static_cast<size_t>(f(t, 2))])
      ++rep.ears;

  auto t0 = Clock::now();
  Points x = disk_embedding(input.vertices, f, loop, domain.boundary);
  rep.seconds_sphere_map = seconds_since(t0);
  rep.initial = surface_metrics(input.vertices, x, f, SurfaceDomain::disk);
  if (rep.initial.flipped_faces > 0)
    throw NumericalError("map_to_disk: the mean value embedding flipped " + std::to_string(rep.initial.flipped_faces) +
                         " faces (a boundary vertex whose faces are all on the circle?)");
  if (opt.progress)
    opt.progress(strprintf("disk embedding: face area mean |r-1| %.4f, %.2f s", rep.initial.face_area_ratio.mean_abs_dev,
                           rep.seconds_sphere_map));
  detail::polish_surface(domain, f, detail::face_areas(input.vertices, f), opt, x, rep);
  res.sphere = std::move(x);
  rep.final = surface_metrics(input.vertices, res.sphere, f, SurfaceDomain::disk);
  rep.converged = rep.final.face_area_ratio.mean_abs_dev <= opt.tolerance;
  rep.seconds_total = seconds_since(t_total);
  return res;
}

}  // namespace vpm
