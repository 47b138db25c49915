// Fields and registrations carried between two meshes of the same solid (vpm/transfer.hpp).
#include "vpm/transfer.hpp"

#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"

namespace vpm {

namespace {

using Eigen::Vector3d;

// The unclamped barycentric coordinates of p in tet t.
std::array<double, 4> raw_barycentric(const Points& x, const Tets& tets, int t, const Vector3d& p) {
  Eigen::Matrix3d e;
  for (int k = 0; k < 3; ++k) e.col(k) = (x.row(tets(t, k + 1)) - x.row(tets(t, 0))).transpose();
  const Vector3d l = e.inverse() * (p - x.row(tets(t, 0)).transpose());
  return {1 - l.sum(), l(0), l(1), l(2)};
}

// Barycentric weights of the point where the segment from p (outside tet t: its raw
// coordinates `raw`, some negative) to the tet's centroid enters the tet. A central projection:
// points outside a convex corner of the mesh stay apart (the closest point of the tet would take
// them all onto the corner vertex: measured, two boundary vertices of a 45,000-vertex brain mesh
// put onto one vertex of a paper-size mesh of it, their tets flat), and a point outside a face
// moves by about its distance from it.
std::array<double, 4> central_projection(const double raw[4]) {
  double t = 1;
  for (int k = 0; k < 4; ++k)
    if (raw[k] < 0) t = std::min(t, 0.25 / (0.25 - raw[k]));
  std::array<double, 4> w{};
  for (int k = 0; k < 4; ++k) w[static_cast<size_t>(k)] = std::max(0.0, 0.25 + t * (raw[k] - 0.25));
  return w;
}

// The point of triangle (a, b, c) closest to p, as weights of a, b, c: its projection onto the
// plane when that lies inside, else the closest point of the nearest edge.
Vector3d closest_on_triangle(const Vector3d& p, const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const Vector3d n = (b - a).cross(c - a);
  const double nn = n.squaredNorm();
  if (nn > 0) {
    const Vector3d q = p - n * (n.dot(p - a) / nn);
    const double wa = n.dot((b - q).cross(c - q)) / nn, wb = n.dot((c - q).cross(a - q)) / nn;
    if (wa >= 0 && wb >= 0 && 1 - wa - wb >= 0) return {wa, wb, 1 - wa - wb};
  }
  const Vector3d* v[3] = {&a, &b, &c};
  Vector3d best(1, 0, 0);
  double best_d = (p - a).squaredNorm();
  for (int e = 0; e < 3; ++e) {
    const Vector3d &s = *v[e], &t = *v[(e + 1) % 3];
    const double len2 = (t - s).squaredNorm();
    const double u = len2 > 0 ? std::clamp((p - s).dot(t - s) / len2, 0.0, 1.0) : 0.0;
    const double d = (p - (s + u * (t - s))).squaredNorm();
    if (d < best_d) {
      best_d = d;
      best.setZero();
      best(e) = 1 - u;
      best((e + 1) % 3) = u;
    }
  }
  return best;
}

// Barycentric weights in tet t for p outside it (raw coordinates `raw`): mostly the tet's point
// closest to p (a point just outside a face moves by its distance), with kCentralShare of the
// central projection above mixed in. The closest point alone takes every point outside a convex
// corner onto the corner vertex: measured, two boundary vertices of a 45,000-vertex brain mesh
// onto one vertex of a paper-size mesh of the same brain, their tets flat and beyond untangling.
constexpr double kCentralShare = 0.2;
std::array<double, 4> outside_weights(const Points& x, const Tets& tets, int t, const Vector3d& p,
                                      const std::array<double, 4>& raw) {
  std::array<double, 4> w{};
  double best = std::numeric_limits<double>::infinity();
  for (int face = 0; face < 4; ++face) {
    int f[3], k = 0;
    for (int j = 0; j < 4; ++j)
      if (j != face) f[k++] = j;
    const Vector3d a = x.row(tets(t, f[0])).transpose(), b = x.row(tets(t, f[1])).transpose(),
                   c = x.row(tets(t, f[2])).transpose();
    const Vector3d l = closest_on_triangle(p, a, b, c);
    const double d = (p - (l(0) * a + l(1) * b + l(2) * c)).squaredNorm();
    if (d < best) {
      best = d;
      w = {};
      for (int j = 0; j < 3; ++j) w[static_cast<size_t>(f[j])] = l(j);
    }
  }
  const std::array<double, 4> central = central_projection(raw.data());
  for (size_t k = 0; k < 4; ++k) w[k] = (1 - kCentralShare) * w[k] + kCentralShare * central[k];
  return w;
}

}  // namespace

Eigen::MatrixXd carry_vertex_field(const TetLocator& from, const Eigen::MatrixXd& values, const Points& points) {
  const Tets& tets = from.tets();
  if (tets.size() > 0 && tets.maxCoeff() >= values.rows())
    throw InputError("carry: the mesh's tets use vertex " + std::to_string(tets.maxCoeff()) + " but the field has " +
                     std::to_string(values.rows()) + " rows");
  const std::vector<Location> loc = from.locate_all(points);
  Eigen::MatrixXd out(points.rows(), values.cols());
  detail::parallel_for(static_cast<int>(points.rows()), 4096, [&](int begin, int end) {
    for (int i = begin; i < end; ++i) {
      const Location& l = loc[static_cast<size_t>(i)];
      std::array<double, 4> w{l.bary[0], l.bary[1], l.bary[2], l.bary[3]};
      if (!l.inside()) {
        const Vector3d p = points.row(i).transpose();
        w = outside_weights(from.vertices(), tets, l.tet, p, raw_barycentric(from.vertices(), tets, l.tet, p));
      }
      out.row(i).setZero();
      for (int k = 0; k < 4; ++k) out.row(i) += w[static_cast<size_t>(k)] * values.row(tets(l.tet, k));
    }
  });
  return out;
}

CarriedRegistration carry_registration(const TetMesh& source, const TetMesh& target) {
  const Points source_native = native_positions(source, "carry: the source mesh");
  const Points target_native = native_positions(target, "carry: the target mesh");
  const TetLocator locator(source_native, source.tets);
  CarriedRegistration out;
  out.ball = carry_vertex_field(locator, Eigen::MatrixXd(source.vertices), target_native);
  const Triangles faces = boundary_faces(target.tets);
  const std::vector<char> boundary = boundary_vertex_mask(target.num_vertices(), faces);
  for (Eigen::Index v = 0; v < out.ball.rows(); ++v)
    if (boundary[static_cast<size_t>(v)]) out.ball.row(v).normalize();
  std::vector<int> folded = inverted_tets(out.ball, target.tets);
  out.folded = static_cast<int>(folded.size());
  for (int rings = 2; rings <= 32 && !folded.empty(); rings *= 2) {
    unflip_sphere_faces(target.vertices, faces, out.ball);
    folded = inverted_tets(out.ball, target.tets);
    if (!folded.empty()) untangle_local(target.vertices, target.tets, out.ball, boundary, folded, rings);
    folded = inverted_tets(out.ball, target.tets);
  }
  out.inverted = static_cast<int>(folded.size());
  return out;
}

}  // namespace vpm
