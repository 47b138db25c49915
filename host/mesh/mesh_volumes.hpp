#pragma once
// Private: signed tet volumes and dual vertex volumes of one tet mesh at changing positions, on
// a device chosen once: the host's threads (vpm::tet_volumes / dual_volumes) when the device is
// the host, else the kernels of kernels/geometry.cl with the connectivity (and, at the first dual
// volumes, the vertex-tet incidence) uploaded once. The volume map asks for both every round and
// after every step (fold checks); vpm::tet_volumes(Device&, ...) and vpm::dual_volumes(Device&,
// ...) are the one-call forms, so the answers are identical.
#include <Eigen/Core>
#include <memory>

#include "vpm/mesh.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

class MeshVolumes {
 public:
  /// `tets` (m x 4) must outlive this object.
  MeshVolumes(Device& device, const Tets& tets);
  ~MeshVolumes();
  MeshVolumes(const MeshVolumes&) = delete;
  MeshVolumes& operator=(const MeshVolumes&) = delete;

  /// vol[t] = det[b-a, c-a, d-a] / 6 at positions x (n x 3).
  Eigen::VectorXd tet_volumes(const Points& x);
  /// dual[v] = a quarter of the volumes of the tets touching v, at positions x.
  Eigen::VectorXd dual_volumes(const Points& x);

 private:
  struct Impl;
  const Tets& tets_;
  std::unique_ptr<Impl> impl_;  // the device's buffers; null on the host
};

}  // namespace vpm::detail
