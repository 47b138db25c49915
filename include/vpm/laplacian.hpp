#pragma once
// The cotangent Laplacian (P1 finite-element stiffness) of a tet mesh and its lumped mass,
// on the host (reference) and on an OpenCL device.
//
// Sign convention (paper eq. 9-10): off-diagonal entries are the cotangent weights
//     K_ij = w_ij = (1/6) sum over tets sharing edge ij of l_kl cot(theta_kl)
//          = -integral grad phi_i . grad phi_j          (kl: the edge opposite ij in that tet,
//                                                        theta_kl: the dihedral angle at kl)
// and K_ii = -sum_{j != i} K_ij, so every row sums to zero and K is NEGATIVE semi-definite:
// (K x)_i approximates the integral of the Laplacian of x over the dual cell of vertex i
// (units: length for K, since w_ij ~ length). The constant vector spans the kernel of K on a
// connected mesh. Weights can be negative for obtuse dihedral angles (3-D cotangent weights).
// Tets are used with their signed volume as given (a flat tet gives inf/NaN: validate first).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/sparse.hpp"

namespace vpm {

class Device;

/// One-call host reference (Eigen triplets): the n x n cotangent stiffness K above for
/// `vertices` (n x 3) and `tets` (m x 4, 0-based). Pattern: symmetric, every vertex's row holds
/// its diagonal and all its edge neighbours, columns sorted.
CsrMatrix cotan_laplacian(const Points& vertices, const Tets& tets);

/// Stateful Laplacian for a fixed connectivity and moving vertices (the flow moves vertices
/// every step). The constructor builds, once, the CSR pattern and a tet-to-slot map on the host;
/// assemble() refreshes the values (and the lumped mass) for new positions: on the host by a
/// scatter over tets, on an OpenCL device by two kernels (per tet weights, then one work item
/// per row gathering from the incident tets through the slot map, no atomics).
class CotanLaplacian {
 public:
  /// `num_vertices` = n (vertices not used by any tet get an empty row except the diagonal 0);
  /// `tets` m x 4, indices in [0, n). Throws InputError on an out-of-range index.
  CotanLaplacian(int num_vertices, const Tets& tets);

  int num_vertices() const { return pattern_.rows; }
  int num_tets() const { return static_cast<int>(tets_.rows()); }
  int nnz() const { return pattern_.nnz(); }
  const Tets& tets() const { return tets_; }

  /// Recomputes K and the lumped mass for `vertices` (n x 3, same length unit throughout) on
  /// `device`. Host device: fills the host values. OpenCL device: the values and mass stay on
  /// the device (device_state()); the host copies (matrix(), mass()) are
  /// downloaded lazily on first access after an assemble. The device must outlive this object
  /// until the next assemble on another device.
  void assemble(Device& device, const Points& vertices);

  /// The CSR matrix K with the values of the last assemble (n x n). Before any assemble the
  /// values are zero.
  const CsrMatrix& matrix() const;
  /// Lumped mass: dual volume of each vertex, a quarter of the signed volumes of its tets
  /// (units^3), length n; sums to the total volume.
  const Eigen::VectorXd& mass() const;

  /// The OpenCL buffers (row_ptr n+1 ints, col nnz ints, val nnz doubles, mass n doubles) of the
  /// last OpenCL assemble, defined in the library's private host/linalg/laplacian_device.hpp.
  /// Throws std::logic_error when no assemble ran on an OpenCL device.
  struct DeviceState;
  DeviceState& device_state();
  /// The device of the last assemble (nullptr before any assemble).
  Device* device() const { return device_; }

  /// For tet t and ordered local corners (a, b), a != b, the index into col/val of entry
  /// (tets(t,a), tets(t,b)): slot_map()[12 t + 3 a + q] where q enumerates b over the three
  /// corners other than a in increasing order. Exposed for tests and for modules that assemble
  /// other per-tet operators on the same pattern.
  const std::vector<int>& slot_map() const { return slot_; }
  /// Index into col/val of the diagonal entry of each row (length n).
  const std::vector<int>& diagonal_slots() const { return diag_; }

 private:
  void download() const;
  Tets tets_;
  mutable CsrMatrix pattern_;  // values = last assembled K (downloaded lazily)
  mutable Eigen::VectorXd mass_;
  mutable bool host_stale_ = false;
  std::vector<int> slot_;
  std::vector<int> diag_;
  Device* device_ = nullptr;
  std::shared_ptr<DeviceState> dev_;  // buffers on the OpenCL device (created on first use)
};

}  // namespace vpm
