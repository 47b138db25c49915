#pragma once
// Private: the OpenCL state of a CotanLaplacian (vpm/laplacian.hpp): the CSR pattern, the
// tet-to-slot map and incidence on the device, the assembled values and lumped mass, and the two
// assembly kernels. The Poisson solver hands row_ptr, col and val to its OpenCL backend.
#include <boost/compute/container/vector.hpp>

#include "core/device_cl.hpp"
#include "vpm/laplacian.hpp"
#include "vpm/topology.hpp"

namespace vpm {

struct CotanLaplacian::DeviceState {
  explicit DeviceState(Device& d) : DeviceState(d.cl().context) {}
  explicit DeviceState(const boost::compute::context& c)
      : tets(c), row_ptr(c), col(c), inc_offset(c), inc_tet(c), slot(c), diag(c), x(c), w(c), vol(c), val(c),
        mass(c) {}
  Device* device = nullptr;
  boost::compute::vector<int> tets, row_ptr, col, inc_offset, inc_tet, slot, diag;
  boost::compute::vector<double> x, w, vol, val, mass;
  boost::compute::kernel k_weights, k_rows;
  Incidence inc;  // kept on the host for the host assembly
};

}  // namespace vpm
