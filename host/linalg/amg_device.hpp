#pragma once
// Private: the multigrid V-cycle of an AmgHierarchy (vpm/amg.hpp) as OpenCL kernels
// (kernels/amg.cl): every level's A, P, R and smoother diagonal in device CSR buffers, the
// coarsest level's dense (pseudo-)inverse as a matrix; apply() only enqueues kernels.
#include <boost/compute/container/vector.hpp>
#include <vector>

#include "core/device_cl.hpp"
#include "vpm/amg.hpp"
#include "vpm/device.hpp"

namespace vpm::detail {

class ClAmg {
 public:
  explicit ClAmg(Device& device);
  /// Copies the hierarchy to the device: buffers and patterns when the level sizes or nnz
  /// changed (or `pattern`), else only the values (after AmgHierarchy::update_values).
  void upload(const AmgHierarchy& h, bool pattern);
  /// Enqueues z = M^-1 f (one V-cycle from zero, the same operations as AmgHierarchy::apply).
  /// f and z: device vectors of length n (distinct).
  void apply(boost::compute::vector<double>& f, boost::compute::vector<double>& z);
  int num_levels() const { return static_cast<int>(levels_.size()); }

 private:
  struct Csr {
    boost::compute::vector<int> row_ptr, col;
    boost::compute::vector<double> val;
    int rows = 0;
  };
  struct Level {
    int n = 0;
    Csr A, P, R;
    boost::compute::vector<double> d, f, out, x, r, t;
  };
  void upload_csr(const CsrMatrix& m, Csr& c, bool pattern);
  void vcycle(int l, boost::compute::vector<double>& f, boost::compute::vector<double>& out);
  Device& dev_;
  int sweeps_ = 1;
  std::vector<Level> levels_;
  boost::compute::vector<double> coarse_inv_;
  boost::compute::kernel k_first_, k_scale_, k_sweep_, k_residual_, k_spmv_, k_prolong_, k_dense_;
};

}  // namespace vpm::detail
