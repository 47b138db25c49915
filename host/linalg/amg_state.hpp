#pragma once
// Private: the AMG preconditioner a solver keeps for one matrix pattern and Dirichlet mask
// (SparseSolver, PoissonSolver): the host hierarchy and, on an OpenCL device, its copy there.
#include <memory>
#include <vector>

#include "linalg/amg_device.hpp"
#include "linalg/solver_backend.hpp"
#include "vpm/amg.hpp"

namespace vpm::detail {

struct AmgState {
  std::vector<char> mask;  ///< the mask the hierarchy was built for
  AmgOptions options;      ///< the options it was built with
  std::unique_ptr<AmgHierarchy> host;
  std::unique_ptr<ClAmg> device;
  bool stale = true;  ///< the matrix values changed since the last build or update

  /// Makes the hierarchy current for matrix `a` and `mask`: a full build when there is none or
  /// the mask or options differ, else (when stale) update_values on the same pattern, then the
  /// upload to `device` (nullptr: host only). Returns the seconds spent.
  double prepare(Device* device, const CsrMatrix& a, const std::vector<char>& mask,
                 const AmgOptions& options);
};

/// Backend b preconditioned with st's hierarchy on b's side (the host's or the device's copy),
/// or with Jacobi when st is null.
inline void use_amg(HostBackend& b, const AmgState* st) { b.set_amg(st ? st->host.get() : nullptr); }
inline void use_amg(ClBackend& b, const AmgState* st) { b.set_amg(st ? st->device.get() : nullptr); }

}  // namespace vpm::detail
