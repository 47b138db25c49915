#pragma once
// Private: signed tet volumes and dual vertex volumes of one tet mesh at changing positions on
// an OpenCL device, with the connectivity (and, at the first dual volumes, the vertex-tet
// incidence) uploaded once. The volume map asks for both every round and after every step
// (fold checks); vpm::tet_volumes(Device&, ...) and vpm::dual_volumes(Device&, ...) are the
// one-call forms of the same kernels (kernels/geometry.cl), so the answers are identical.
#include <Eigen/Core>
#include <memory>

#include "vpm/mesh.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

class DeviceVolumes {
 public:
  /// `tets` (m x 4) must outlive this object; `device` must not be the host.
  DeviceVolumes(Device& device, const Tets& tets);
  ~DeviceVolumes();
  DeviceVolumes(const DeviceVolumes&) = delete;
  DeviceVolumes& operator=(const DeviceVolumes&) = delete;

  /// vol[t] = det[b-a, c-a, d-a] / 6 at positions x (n x 3).
  Eigen::VectorXd tet_volumes(const Points& x);
  /// dual[v] = a quarter of the volumes of the tets touching v, at positions x.
  Eigen::VectorXd dual_volumes(const Points& x);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm::detail
