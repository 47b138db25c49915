#pragma once
// Geometric quantities of tet meshes, on the host (Eigen reference) and on an OpenCL device.
#include <Eigen/Core>

#include "vpm/mesh.hpp"

namespace vpm {

class Device;

/// Signed volumes of the m tets: det[v1-v0, v2-v0, v3-v0] / 6 (units^3). Length m.
Eigen::VectorXd tet_volumes(const Points& vertices, const Tets& tets);
/// Same, computed by the kernel `geometry.tet_volumes` on `device` (host device: the above).
Eigen::VectorXd tet_volumes(Device& device, const Points& vertices, const Tets& tets);

/// Barycentric dual volume of each of the n vertices: a quarter of the summed signed volumes
/// of its tets. Sums to the total volume. Length n.
Eigen::VectorXd dual_volumes(const Points& vertices, const Tets& tets);
Eigen::VectorXd dual_volumes(Device& device, const Points& vertices, const Tets& tets);

/// The six dihedral angles of each tet in degrees, m x 6, for edges
/// (0,1),(0,2),(0,3),(1,2),(1,3),(2,3); an angle beside a zero-area face is 0.
Eigen::Matrix<double, Eigen::Dynamic, 6, Eigen::RowMajor> dihedral_angles_deg(const Points& vertices,
                                                                             const Tets& tets);

/// The smallest of each tet's six dihedral angles in degrees, length m: the row minima of
/// dihedral_angles_deg (the same face-normal cosines), with one arccosine per tet instead of six.
/// 0 for a tet with a zero-area face.
Eigen::VectorXd min_dihedral_angles_deg(const Points& vertices, const Tets& tets);

}  // namespace vpm
