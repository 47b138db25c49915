// Landmarks without atlas labels: point pairs under the affine that matches the two native
// solids' volume moments (vpm/collective.hpp, moment_landmarks).
#include <Eigen/Eigenvalues>
#include <cmath>
#include <vector>

#include "vpm/collective.hpp"
#include "vpm/error.hpp"
#include "vpm/locate.hpp"

namespace vpm {
namespace {

struct Moments {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
};

// Volume centroid and covariance of the solid (exact for linear tets: the integral of x x^T over a
// tet is V/20 (sum v_i v_i^T + s s^T), s = sum v_i).
Moments solid_moments(const Points& x, const Tets& tets) {
  double volume = 0;
  Eigen::Vector3d first = Eigen::Vector3d::Zero();
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    Eigen::Vector3d v[4];
    for (int k = 0; k < 4; ++k) v[k] = x.row(tets(t, k)).transpose();
    const double vol = std::abs((v[1] - v[0]).dot((v[2] - v[0]).cross(v[3] - v[0]))) / 6;
    const Eigen::Vector3d s = v[0] + v[1] + v[2] + v[3];
    Eigen::Matrix3d vv = s * s.transpose();
    for (int k = 0; k < 4; ++k) vv += v[k] * v[k].transpose();
    volume += vol;
    first += vol * s / 4;
    second += vol / 20 * vv;
  }
  if (!(volume > 0)) throw InputError("moment landmarks: a mesh of zero volume");
  Moments m;
  m.centroid = first / volume;
  m.covariance = second / volume - m.centroid * m.centroid.transpose();
  return m;
}

Eigen::Matrix3d sqrt_spd(const Eigen::Matrix3d& a, bool inverse) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(a);
  Eigen::Vector3d d = es.eigenvalues();
  if (!(d.minCoeff() > 0)) throw InputError("moment landmarks: a mesh whose second moments are degenerate (flat solid)");
  for (int i = 0; i < 3; ++i) d(i) = inverse ? 1 / std::sqrt(d(i)) : std::sqrt(d(i));
  return es.eigenvectors() * d.asDiagonal() * es.eigenvectors().transpose();
}

// The fixed ball points: the centre and the 12 icosahedron directions at radii 0.35 and 0.7.
Points probe_points() {
  const double p = (1 + std::sqrt(5.0)) / 2;
  const double dirs[12][3] = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                              {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
  Points out(25, 3);
  out.row(0).setZero();
  for (int r = 0; r < 2; ++r)
    for (int i = 0; i < 12; ++i)
      out.row(1 + 12 * r + i) = Eigen::RowVector3d(dirs[i][0], dirs[i][1], dirs[i][2]).normalized() * (r ? 0.7 : 0.35);
  return out;
}

}  // namespace

MomentLandmarks moment_landmarks(const TetMesh& moving, const TetMesh& fixed) {
  const Points native_m = native_positions(moving, "moving mesh");
  const Points native_f = native_positions(fixed, "fixed mesh");
  const Moments mm = solid_moments(native_m, moving.tets), mf = solid_moments(native_f, fixed.tets);
  MomentLandmarks r;
  r.linear = sqrt_spd(mf.covariance, false) * sqrt_spd(mm.covariance, true);
  r.moving_centroid = mm.centroid;
  r.fixed_centroid = mf.centroid;
  const Points probes = probe_points();
  const Points fixed_native = pull_back_points(probes, fixed.vertices, fixed.tets, native_f);
  const Eigen::Matrix3d back = r.linear.inverse();
  Points moving_native(probes.rows(), 3);
  for (Eigen::Index i = 0; i < probes.rows(); ++i)
    moving_native.row(i) = (back * (fixed_native.row(i).transpose() - mf.centroid) + mm.centroid).transpose();
  const TetLocator locator(native_m, moving.tets);
  std::vector<Eigen::Index> kept;
  std::vector<Eigen::RowVector3d> ball;
  for (Eigen::Index i = 0; i < probes.rows(); ++i) {
    const Location loc = locator.locate(moving_native.row(i).transpose());
    if (loc.tet < 0 || !loc.inside()) {
      ++r.dropped;
      continue;
    }
    Eigen::RowVector3d b = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) b += loc.bary[k] * moving.vertices.row(moving.tets(loc.tet, k));
    kept.push_back(i);
    ball.push_back(b);
  }
  if (kept.size() < 4)
    throw InputError("moment landmarks: only " + std::to_string(kept.size()) +
                     " of 25 points land inside the moving mesh after the moments' affine (native frames far apart?)");
  r.source.resize(static_cast<Eigen::Index>(kept.size()), 3);
  r.target.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t j = 0; j < kept.size(); ++j) {
    r.source.row(static_cast<Eigen::Index>(j)) = ball[j];
    r.target.row(static_cast<Eigen::Index>(j)) = probes.row(kept[j]);
  }
  return r;
}

}  // namespace vpm
