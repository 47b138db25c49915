// vpm::boundary_tet_ratio_bound (vpm/initial_map.hpp): how crowded a fixed boundary on the
// sphere leaves the tets on it, whatever the interior.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "vpm/geometry.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/topology.hpp"

namespace vpm {

double boundary_tet_ratio_bound(const TetMesh& m, const Points& sphere) {
  std::vector<int> face_tet;
  const Triangles faces = boundary_faces(m.tets, &face_tet);
  const Eigen::VectorXd v0 = tet_volumes(m.vertices, m.tets);
  double enclosed = 0, least = std::numeric_limits<double>::infinity();
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = sphere.row(faces(f, 0)), b = sphere.row(faces(f, 1)), c = sphere.row(faces(f, 2));
    const Eigen::Vector3d n = (b - a).cross(c - a);
    enclosed += a.dot(b.cross(c)) / 6;
    const double area2 = n.norm();  // twice the area
    const double h = 1 + (area2 > 0 ? std::abs(n.dot(a)) / area2 : 1.0);
    least = std::min(least, area2 / 2 * h / 3 / v0(face_tet[static_cast<size_t>(f)]));
  }
  return least * v0.sum() / std::abs(enclosed);
}

}  // namespace vpm
