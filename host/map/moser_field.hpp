#pragma once
// Private: the fixed field of one Moser round on its background mesh (point location:
// mesh/tet_grid.hpp), and the RK4 advection of all vertices along their pathlines, on the host
// and on an OpenCL device (kernels/moser.cl); the per-point arithmetic (velocity, RK4 step,
// gradients) is written once in kernels/moser_field.clh, compiled by both.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "mesh/tet_grid.hpp"
#include "vpm/mesh.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// The fixed field of one Moser round on its background mesh (a TetGrid for point location):
/// vertex gradients of psi and rho0.
struct MoserField : TetGrid {
  std::vector<double> grad;          ///< n x 3: vertex gradients of psi
  std::vector<double> rho0;          ///< n: m_i / V_i
};

/// Per-tet gradients of the P1 function `psi` (length n) on the background (m x 3), from inv.
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> tet_gradients(const MoserField& f,
                                                                       const Eigen::VectorXd& psi);

/// Vertex gradients (eq. 13, n x 3): the volume-weighted averages of the per-tet gradients G
/// (vol: signed tet volumes on x), the normal x/|x| part removed at boundary vertices (the
/// whole vector when `slide` is false). kernels/moser.cl computes the same on a device.
std::vector<double> vertex_gradients(const Tets& tets, const Points& x,
                                     const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& G,
                                     const Eigen::VectorXd& vol, const std::vector<char>& boundary,
                                     bool slide);

struct AdvectStats {
  long long locations = 0;
  long long walk_steps = 0;
  long long grid_fallbacks = 0;
  long long clamped = 0;
};

struct AdvectParams {
  int steps = 40;       ///< RK4 steps over [0, t_end]
  double t_end = 1;
  bool slide = true;    ///< boundary vertices slide on the sphere (else fixed)
};

/// Host reference: moves `x` (n x 3) along the field from t = 0 to t_end. `hint` (n) holds a
/// tet containing (or near) each point at the start; updated. `boundary` n entries.
void advect_host(const MoserField& f, const std::vector<char>& boundary, const AdvectParams& p,
                 Points& x, std::vector<int>& hint, AdvectStats* stats);

/// A Moser round's advection where the map's Placement put it (the host's threads or an OpenCL
/// device): made once per map, then called without knowing which.
class Advector {
 public:
  virtual ~Advector() = default;
  /// The round's field f (background, rho0, grad). f must then live unchanged until
  /// release_field() or the next set_field: the host's advector reads it in place, the device's
  /// views its big arrays on CPU devices (elsewhere it copies them).
  virtual void set_field(const MoserField& f) = 0;
  /// Drops what the last set_field kept of f (call before that MoserField changes or goes).
  virtual void release_field() = 0;
  /// Moves x (n x 3) along the field from t = 0 to p.t_end; `hint` (n) in/out as advect_host's.
  virtual void advect(const AdvectParams& p, Points& x, std::vector<int>& hint, AdvectStats* stats) = 0;
  /// Whether it runs on an OpenCL device.
  virtual bool on_device() const = 0;
};

/// advect_host behind the Advector interface; `boundary` (n entries) must outlive it.
class HostAdvector final : public Advector {
 public:
  explicit HostAdvector(const std::vector<char>& boundary) : boundary_(boundary) {}
  void set_field(const MoserField& f) override { field_ = &f; }
  void release_field() override { field_ = nullptr; }
  void advect(const AdvectParams& p, Points& x, std::vector<int>& hint, AdvectStats* stats) override;
  bool on_device() const override { return false; }

 private:
  const std::vector<char>& boundary_;
  const MoserField* field_ = nullptr;
};

/// OpenCL advection: connectivity and boundary uploaded once; per round the background
/// (set_field), then advect() keeps positions on the device for the whole round and reads them
/// back once.
class DeviceAdvector final : public Advector {
 public:
  DeviceAdvector(Device& device, const Tets& tets, const std::vector<int>& nbr,
                 const std::vector<char>& boundary);
  ~DeviceAdvector() override;
  /// The round's background and field from the host: f's inverse matrices, grid, rho0 and grad.
  /// On CPU devices the inverse matrices and the grid's lists are not copied but used where f
  /// holds them: f must then live unchanged until release_field() (or the next set_field).
  void set_field(const MoserField& f) override;
  /// Drops the views of the last set_field's host arrays (call before that MoserField goes).
  void release_field() override;
  /// The same background with the inverse matrices and the vertex gradients computed on the
  /// device (f.inv and f.grad are not read: build_grid suffices): the inverses from x
  /// (kernels/moser.cl, equal to build_background's to round-off), the gradients from psi
  /// (paper eq. 12-13): per-tet gradients from the inverses, their volume-weighted vertex
  /// averages, the normal part removed at boundary vertices (the whole vector when `slide` is
  /// false); the same arithmetic as tet_gradients and the volume map's host averaging. `x`: the
  /// background's positions. Only psi, x and the grid go up (not 12 doubles a tet), nothing
  /// comes back.
  void set_field(const MoserField& f, const Eigen::VectorXd& psi, const Points& x, bool slide);
  /// The vertex gradients now on the device (n x 3), for tests.
  std::vector<double> gradients();
  /// The background's inverse matrices now on the device (m x 12, TetGrid::inv), for tests.
  std::vector<double> inverses();
  void advect(const AdvectParams& p, Points& x, std::vector<int>& hint, AdvectStats* stats) override;
  bool on_device() const override { return true; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm::detail
