// Mean curvature by the cotangent Laplacian (vpm/curvature.hpp).
#include "vpm/curvature.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace vpm {

Eigen::VectorXd mean_curvature(const TriSurface& s) {
  const Eigen::Index n = s.vertices.rows();
  Points lap = Points::Zero(n, 3), normal = Points::Zero(n, 3);
  Eigen::VectorXd area = Eigen::VectorXd::Zero(n);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const int v[3] = {s.triangles(t, 0), s.triangles(t, 1), s.triangles(t, 2)};
    const Eigen::RowVector3d cross = (s.vertices.row(v[1]) - s.vertices.row(v[0])).cross(s.vertices.row(v[2]) - s.vertices.row(v[0]));
    const double twice = cross.norm();
    if (!(twice > 0)) continue;
    for (int k = 0; k < 3; ++k) {
      const int i = v[k], j = v[(k + 1) % 3], l = v[(k + 2) % 3];
      // the angle at i is opposite the edge j-l: (cot / 2) (x_l - x_j) at j and back at l
      const Eigen::RowVector3d u = s.vertices.row(j) - s.vertices.row(i), w = s.vertices.row(l) - s.vertices.row(i);
      const double half_cot = u.dot(w) / twice / 2;
      lap.row(j) += half_cot * (s.vertices.row(l) - s.vertices.row(j));
      lap.row(l) += half_cot * (s.vertices.row(j) - s.vertices.row(l));
      normal.row(i) += cross;
      area(i) += twice / 6;
    }
  }
  Eigen::VectorXd h = Eigen::VectorXd::Zero(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double len = normal.row(i).norm();
    if (area(i) > 0 && len > 0) h(i) = -lap.row(i).dot(normal.row(i) / len) / (2 * area(i));
  }
  return h;
}

}  // namespace vpm
