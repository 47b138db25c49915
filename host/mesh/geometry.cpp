#include "vpm/geometry.hpp"

#include <Eigen/Geometry>
#include <boost/compute/container/vector.hpp>
#include <cmath>

#include "core/parallel.hpp"
#include "mesh/mesh_volumes.hpp"
#include "mesh/tet_geometry.hpp"
#include "core/device_cl.hpp"
#include "vpm/device.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace bc = boost::compute;

Eigen::VectorXd tet_volumes(const Points& x, const Tets& t) {
  Eigen::VectorXd vol(t.rows());
  detail::parallel_for(static_cast<int>(t.rows()), 32768, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      double e[3][3];
      detail::tet_edges(x, t, i, e);
      vol(i) = detail::tg_volume(e[0], e[1], e[2]);
    }
  });
  return vol;
}

Eigen::VectorXd dual_volumes(const Points& x, const Tets& t) {
  const Eigen::VectorXd vol = tet_volumes(x, t);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(x.rows());
  for (Eigen::Index i = 0; i < t.rows(); ++i)
    for (int c = 0; c < 4; ++c) d(t(i, c)) += 0.25 * vol(i);
  return d;
}

Eigen::VectorXd tet_volumes(Device& dev, const Points& x, const Tets& t) {
  if (t.rows() == 0) return tet_volumes(x, t);
  return detail::MeshVolumes(dev, t).tet_volumes(x);
}

Eigen::VectorXd dual_volumes(Device& dev, const Points& x, const Tets& t) {
  if (t.rows() == 0) return dual_volumes(x, t);
  return detail::MeshVolumes(dev, t).dual_volumes(x);
}

namespace {
// The cosines of tet i's six dihedral angles, edges in dihedral_angles_deg's order. The angle at
// edge (a, b) is the one between the inward normals of the two faces opposite c and d (the
// other two corners), turned: cos = -n_c . n_d; the inward normals are the barycentric
// gradients, up to one common factor 1 / (6 V) that the cosine cancels. An edge with a
// zero-area face beside it gets cosine 1 (angle 0).
void dihedral_cosines(const Points& x, const Tets& t, Eigen::Index i, double cosine[6]) {
  static constexpr int kOther[6][2] = {{2, 3}, {1, 3}, {1, 2}, {0, 3}, {0, 2}, {0, 1}};
  const Eigen::Vector3d p0 = x.row(t(i, 0)).transpose();
  const Eigen::Vector3d e1 = x.row(t(i, 1)).transpose() - p0, e2 = x.row(t(i, 2)).transpose() - p0,
                        e3 = x.row(t(i, 3)).transpose() - p0;
  Eigen::Vector3d g[4];
  g[1] = e2.cross(e3);
  g[2] = e3.cross(e1);
  g[3] = e1.cross(e2);
  g[0] = -(g[1] + g[2] + g[3]);
  double len[4];
  for (int k = 0; k < 4; ++k) len[k] = g[k].norm();
  for (int e = 0; e < 6; ++e) {
    const int c = kOther[e][0], d = kOther[e][1];
    cosine[e] = len[c] == 0 || len[d] == 0 ? 1.0 : -g[c].dot(g[d]) / (len[c] * len[d]);
  }
}

double angle_deg(double cosine) { return std::acos(std::clamp(cosine, -1.0, 1.0)) * 180.0 / M_PI; }
}  // namespace

Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> dihedral_angles_deg(const Points& x,
                                                                             const Tets& t) {
  Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> out(t.rows(), 6);
  detail::parallel_for(static_cast<int>(t.rows()), 16384, [&](int i0, int i1) {
    double c[6];
    for (int i = i0; i < i1; ++i) {
      dihedral_cosines(x, t, i, c);
      for (int e = 0; e < 6; ++e) out(i, e) = angle_deg(c[e]);
    }
  });
  return out;
}

Eigen::VectorXd min_dihedral_angles_deg(const Points& x, const Tets& t) {
  Eigen::VectorXd out(t.rows());
  detail::parallel_for(static_cast<int>(t.rows()), 16384, [&](int i0, int i1) {
    double c[6];
    for (int i = i0; i < i1; ++i) {
      dihedral_cosines(x, t, i, c);
      out(i) = angle_deg(*std::max_element(c, c + 6));  // the largest cosine: the smallest angle
    }
  });
  return out;
}

}  // namespace vpm
