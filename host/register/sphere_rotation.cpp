// The rotation search of a dense registration without landmarks (sphere_rotation.hpp).
#include "register/sphere_rotation.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <vector>

#include "register/dense_surface.hpp"
#include "vpm/icosphere.hpp"

namespace vpm::detail {

namespace {

// The scalars are compared at an icosphere's vertices (642, level 3: about 0.15 rad apart, a
// quarter of the scale they are smoothed at).
constexpr int kSampleLevel = 3;
// The grid: axes at an icosphere's vertices (42, level 1; both signs), angles in steps of 0.5 rad.
constexpr int kAxisLevel = 1;
constexpr double kAngleStep = 0.5;
// The pattern search starts from the grid's best few, with steps of kStart rad about each axis,
// halved down to kStop.
constexpr int kStarts = 3;
constexpr double kStart = 0.25, kStop = 0.002;

Eigen::VectorXd interpolate(const SphereLocator& loc, const Eigen::VectorXd& v, const Points& at) {
  const std::vector<SphereLocation> l = loc.locate_all(at);
  Eigen::VectorXd out(at.rows());
  for (Eigen::Index k = 0; k < at.rows(); ++k) {
    const SphereLocation& s = l[static_cast<size_t>(k)];
    out(k) = 0;
    for (int c = 0; c < 3; ++c) out(k) += s.bary[c] * v(loc.faces()(s.face, c));
  }
  return out;
}

double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  const Eigen::VectorXd ca = a.array() - a.mean(), cb = b.array() - b.mean();
  const double d = std::sqrt(ca.squaredNorm() * cb.squaredNorm());
  return d > 0 ? ca.dot(cb) / d : 0;
}

Eigen::Matrix3d rotation(const Eigen::Vector3d& axis_angle) {
  const double a = axis_angle.norm();
  return a > 0 ? Eigen::AngleAxisd(a, axis_angle / a).toRotationMatrix() : Eigen::Matrix3d::Identity();
}

struct Candidate {
  Eigen::Matrix3d r;
  double c;
};

}  // namespace

RotationFound search_rotation(const Points& x, const Triangles& faces, const Eigen::VectorXd& f, const SphereLocator& templ,
                              const Eigen::VectorXd& g) {
  const Points u = icosphere(kSampleLevel).vertices;
  const Eigen::VectorXd fu = interpolate(SphereLocator(x, faces), f, u);
  auto score = [&](const Eigen::Matrix3d& r) { return correlation(fu, interpolate(templ, g, u * r.transpose())); };
  RotationFound out;
  out.correlation = out.correlation_identity = score(Eigen::Matrix3d::Identity());
  if (out.correlation_identity >= kAligned) return out;
  std::vector<Candidate> grid{{Eigen::Matrix3d::Identity(), out.correlation_identity}};
  const Points axes = icosphere(kAxisLevel).vertices;
  for (Eigen::Index i = 0; i < axes.rows(); ++i)
    for (double a = kAngleStep; a < M_PI + 1e-9; a += kAngleStep) {
      const Eigen::Matrix3d r = rotation(a * axes.row(i).transpose().normalized());
      grid.push_back({r, score(r)});
    }
  std::partial_sort(grid.begin(), grid.begin() + kStarts, grid.end(), [](const Candidate& p, const Candidate& q) { return p.c > q.c; });
  Candidate best = grid[0];
  for (int s = 0; s < kStarts; ++s) {
    Candidate at = grid[static_cast<size_t>(s)];
    for (double step = kStart; step >= kStop;) {
      Candidate next = at;
      for (int k = 0; k < 6; ++k) {
        const Eigen::Matrix3d r = rotation((k % 2 ? -step : step) * Eigen::Vector3d::Unit(k / 2)) * at.r;
        const double c = score(r);
        if (c > next.c) next = {r, c};
      }
      if (next.c > at.c) at = next;
      else step /= 2;
    }
    if (at.c > best.c) best = at;
  }
  out.rotation = best.r;
  out.correlation = best.c;
  return out;
}

}  // namespace vpm::detail
