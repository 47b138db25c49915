// Repair of boundary triangles flipped on the unit sphere (vpm/untangle.hpp).
#include <Eigen/Geometry>

#include "vpm/error.hpp"
#include "vpm/untangle.hpp"

namespace vpm {

std::vector<int> flipped_sphere_faces(const Triangles& faces, const Points& x) {
  std::vector<int> out;
  for (Eigen::Index f = 0; f < faces.rows(); ++f) {
    const Eigen::Vector3d a = x.row(faces(f, 0)).transpose(), b = x.row(faces(f, 1)).transpose(),
                          d = x.row(faces(f, 2)).transpose();
    if (!(a.dot(b.cross(d)) > 0)) out.push_back(static_cast<int>(f));
  }
  return out;
}

int unflip_sphere_faces(const Points& reference, const Triangles& faces, Points& x,
                        const std::vector<char>& pinned) {
  std::vector<int> flipped = flipped_sphere_faces(faces, x);
  if (flipped.empty()) return 0;
  const int n = static_cast<int>(x.rows()), nf = static_cast<int>(faces.rows());
  // Vertices 0..n-1 as they are, then one apex per face at the origin (fixed).
  Points p = Points::Zero(n + nf, 3), r = Points::Zero(n + nf, 3);
  p.topRows(n) = x;
  r.topRows(n) = reference;
  Tets cone(nf, 4);
  std::vector<char> fixed(static_cast<size_t>(n + nf), 1), on_face(static_cast<size_t>(n), 0);
  for (int f = 0; f < nf; ++f) {
    cone(f, 0) = n + f;
    for (int k = 0; k < 3; ++k) {
      cone(f, k + 1) = faces(f, k);
      const int v = faces(f, k);
      const bool pin = !pinned.empty() && pinned[static_cast<size_t>(v)];
      fixed[v] = pin ? 1 : 0;
      on_face[v] = pin ? 0 : 1;
    }
  }
  for (int rings = 2; rings <= 4 && !flipped.empty(); rings += 2) {
    try {
      untangle_local(r, cone, p, fixed, flipped, rings, untangle_local_options());
    } catch (const InputError&) {
      // a reference cone near one of these faces is itself degenerate or flipped (a sliver
      // triangle of `reference` on the sphere): no shape to restore here; the tet untangling
      // that follows repairs (or reports) what is left
      break;
    }
    flipped = flipped_sphere_faces(faces, p);
  }
  for (int v = 0; v < n; ++v)
    if (on_face[v]) x.row(v) = p.row(v).normalized();
  return static_cast<int>(flipped_sphere_faces(faces, x).size());
}

}  // namespace vpm
