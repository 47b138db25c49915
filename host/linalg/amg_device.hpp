#pragma once
// Private: the OpenCL backend of an AmgHierarchy's V-cycle (vpm/amg.hpp, linalg/amg_vcycle.hpp:
// the kernels of kernels/amg.cl): every level's A, P, R and smoother diagonal in device CSR buffers, the
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

  /// amg_vcycle's backend (linalg/amg_vcycle.hpp): each primitive enqueues one kernel.
  using Vec = boost::compute::vector<double>*;
  int levels() const { return num_levels(); }
  int sweeps() const { return sweeps_; }
  void work(int l, Vec& x, Vec& r, Vec& t);
  void coarse_vectors(int l, Vec& f, Vec& out);
  void first(int l, Vec f, Vec x, Vec r);
  void scale(int l, Vec f, Vec x);
  void sweep(int l, Vec f, Vec in, Vec o);
  void residual(int l, Vec f, Vec x, Vec r);
  void restrict_to(int l, Vec r, Vec fc);
  void prolong(int l, Vec xc, Vec x, Vec t);
  void coarse(int l, Vec f, Vec out);

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
  Device& dev_;
  int sweeps_ = 1;
  std::vector<Level> levels_;
  boost::compute::vector<double> coarse_inv_;
  boost::compute::kernel k_first_, k_scale_, k_sweep_, k_residual_, k_spmv_, k_prolong_, k_dense_;
};

}  // namespace vpm::detail
