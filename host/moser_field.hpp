#pragma once
// Private: the fixed field of one Moser round on its background mesh, point location, and the
// RK4 advection of all vertices along their pathlines, on the host (reference) and on an
// OpenCL device (kernels/moser.cl, same algorithm line for line).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// nbr[4 t + k] = the tet sharing the face of tet t opposite its corner k, or -1 (boundary).
std::vector<int> tet_neighbors(const Tets& tets);

/// Background data of one round: geometry for barycentric coordinates, the vertex field, and a
/// uniform grid of tets for the fallback search.
struct MoserField {
  int n = 0, m = 0;
  const Tets* tets = nullptr;        ///< m x 4 (owned by the caller)
  const std::vector<int>* nbr = nullptr;
  std::vector<double> inv;           ///< m x 12: corner a, then rows of [b-a, c-a, d-a]^-1
  std::vector<double> grad;          ///< n x 3: vertex gradients of psi
  std::vector<double> rho0;          ///< n: m_i / V_i
  double lo[3] = {0, 0, 0};
  double inv_h = 1;
  int dims[3] = {1, 1, 1};
  std::vector<int> cell_start;       ///< cells + 1
  std::vector<int> cell_tets;
};

/// Fills inv and the grid of `f` for background positions `x` (n x 3).
void build_background(MoserField& f, const Points& x, const Tets& tets, const std::vector<int>& nbr);

/// Per-tet gradients of the P1 function `psi` (length n) on the background (m x 3), from inv.
Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> tet_gradients(const MoserField& f,
                                                                       const Eigen::VectorXd& psi);

/// Barycentric coordinates l[0..3] of `p` in tet `t` of the background `f`.
void bary(const MoserField& f, int t, const Eigen::Vector3d& p, double* l);

/// Point location: walks from tet `t` towards `p` through face neighbours (at most 64 steps),
/// else searches the grid cell of `p`. Returns the tet containing `p` with its barycentric
/// coordinates in `l`; a point outside the mesh gets the best tet found and coordinates clamped
/// to it. `st` (3 counters: walk steps, grid fallbacks, clamped) is incremented.
int locate(const MoserField& f, const Eigen::Vector3d& p, int t, double* l, long long* st);

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

/// OpenCL advection: connectivity and boundary uploaded once; per round the background
/// (set_field), then advect() keeps positions on the device for the whole round and reads them
/// back once.
class DeviceAdvector {
 public:
  DeviceAdvector(Device& device, const Tets& tets, const std::vector<int>& nbr,
                 const std::vector<char>& boundary);
  ~DeviceAdvector();
  void set_field(const MoserField& f);
  void advect(const AdvectParams& p, Points& x, std::vector<int>& hint, AdvectStats* stats);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vpm::detail
