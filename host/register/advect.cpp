// ---- advection: K RK4 steps through the fields, on the host or the device, written once
// (kernels/rbf_advect.clh): the ball's RBF fields (advect), the sphere's (advect_on_sphere) and the
// disk's (advect_in_disk) ----
#include <algorithm>
#include <cmath>

#include <boost/compute/container/vector.hpp>

#include "register/registration_steps.hpp"
#include "register/disk_field.hpp"
#include "register/sphere_field.hpp"
#include "core/device_cl.hpp"
#include "core/parallel.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/mesh_order.hpp"

namespace vpm {

namespace detail {
// the grid of centres, the cut and RK4 of LANES points (here 1), shared with kernels/register.cl
#include "kernels/rbf_advect.clh"
}  // namespace detail

namespace bc = boost::compute;

namespace {

/// Advection leaves out a centre whose Gaussian exp(-lambda r^2) is below exp(-kFieldCut) at
/// every point of a call (one on the host, a work item's lanes on the device): its terms are at
/// most about 32 exp(-32) = 4e-13 of a near centre's, far below what the integration resolves.
constexpr double kFieldCut = 32;

/// The distinct fields packed for the kernel: each field's centres and coefficients sorted by
/// the cell of a grid shared by all fields (x fastest), one after the other; `cells` holds each
/// field's g^3 + 1 cell starts (absolute indices) and `slot` the field of each of the 2K + 1
/// stage slots. Cells are half the reach (the distance past which every term is cut), so a point
/// visits the few rows of cells near it instead of all the centres (at width 0.1 about a fifth).
struct PackedFields {
  std::vector<double> centres, coefs;
  std::vector<int> cells, slot;
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  double side = 1, reach = 1;
  int g = 1;
};

/// Fields with fewer centres than this get one cell: finding a point's span of cells costs more
/// than the few centres it would skip (register benchmark, 20 landmarks: the advection 1.3x
/// slower with a 4^3 grid; the demo's dense fields of 171-1,551 centres: faster with it).
constexpr Eigen::Index kGridMinCentres = 64;

/// The shared grid: the box of all the centres, cells of about reach / 2, at most 32 a side (32^3
/// + 1 starts a field); one cell when no field has kGridMinCentres centres.
void grid_for(const std::vector<DivFreeField>& f, PackedFields& pk) {
  pk.reach = std::sqrt(kFieldCut / f[0].lambda) * (1 + 1e-9);  // a hair wide: rounding never cuts a kept term
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(0), hi = lo;
  bool any = false;
  for (const auto& field : f)
    if (field.centres.rows() > 0) {
      const Eigen::Vector3d a = field.centres.colwise().minCoeff().transpose(),
                            b = field.centres.colwise().maxCoeff().transpose();
      lo = any ? lo.cwiseMin(a) : a;
      hi = any ? hi.cwiseMax(b) : b;
      any = true;
    }
  const double extent = (hi - lo).maxCoeff();
  Eigen::Index most = 0;
  for (const auto& field : f) most = std::max(most, field.centres.rows());
  pk.g = most < kGridMinCentres ? 1 : static_cast<int>(std::clamp(std::ceil(extent / (0.5 * pk.reach)), 1.0, 32.0));
  pk.side = extent > 0 ? extent / pk.g : 1.0;
  pk.origin = lo;
}

int cell_of(const PackedFields& pk, const Eigen::Vector3d& y) {
  int c[3];
  for (int a = 0; a < 3; ++a)
    c[a] = std::clamp(static_cast<int>(std::floor((y(a) - pk.origin(a)) / pk.side)), 0, pk.g - 1);
  return (c[2] * pk.g + c[1]) * pk.g + c[0];
}

/// Appends one field's centres and coefficients in cell order and its cell starts.
void pack_field(const DivFreeField& field, PackedFields& pk) {
  const int base = static_cast<int>(pk.centres.size() / 3), ncell = pk.g * pk.g * pk.g;
  const Eigen::Index n = field.centres.rows();
  std::vector<int> cell(static_cast<size_t>(n)), start(static_cast<size_t>(ncell) + 1, 0);
  for (Eigen::Index j = 0; j < n; ++j) {
    cell[static_cast<size_t>(j)] = cell_of(pk, field.centres.row(j).transpose());
    ++start[static_cast<size_t>(cell[static_cast<size_t>(j)]) + 1];
  }
  for (int c = 0; c < ncell; ++c) start[static_cast<size_t>(c) + 1] += start[static_cast<size_t>(c)];
  std::vector<int> next(start.begin(), start.end() - 1);
  pk.centres.resize(pk.centres.size() + 3 * static_cast<size_t>(n));
  pk.coefs.resize(pk.coefs.size() + 3 * static_cast<size_t>(n));
  for (Eigen::Index j = 0; j < n; ++j) {
    const size_t at = 3 * static_cast<size_t>(base + next[static_cast<size_t>(cell[static_cast<size_t>(j)])]++);
    for (int a = 0; a < 3; ++a) {
      pk.centres[at + static_cast<size_t>(a)] = field.centres(j, a);
      pk.coefs[at + static_cast<size_t>(a)] = field.coefficients(j, a);
    }
  }
  for (const int s : start) pk.cells.push_back(base + s);
}

PackedFields pack_fields(const std::vector<DivFreeField>& f, int steps) {
  PackedFields pk;
  grid_for(f, pk);
  for (const auto& field : f) pack_field(field, pk);
  for (int s = 0; s <= 2 * steps; ++s) pk.slot.push_back(f.size() == 1 ? 0 : s);
  if (pk.centres.empty()) {
    pk.centres.assign(3, 0.0);
    pk.coefs.assign(3, 0.0);
  }
  return pk;
}

// The host: rbf_advect.clh's rk4_points one point at a time (LANES 1) on the host threads.
// `kind`: rbf_advect.clh's (0 free, 1 tangent, 2 the sphere's, 3 the disk's).
void advect_host(Points& x, const std::vector<DivFreeField>& f, int steps, int kind) {
  const PackedFields pk = pack_fields(f, steps);
  const detail::CentreGrid grid = {pk.origin(0), pk.origin(1), pk.origin(2), pk.side, pk.g};
  detail::parallel_for(static_cast<int>(x.rows()), 64, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      double p0 = x(i, 0), p1 = x(i, 1), p2 = x(i, 2);
      detail::rk4_points(&p0, &p1, &p2, steps, 1.0 / steps, pk.slot.data(), pk.cells.data(), grid, pk.reach,
                         pk.centres.data(), pk.coefs.data(), f[0].lambda, kFieldCut, kind);
      x(i, 0) = p0;
      x(i, 1) = p1;
      x(i, 2) = p2;
    }
  });
}

void advect_device(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps, int kind) {
  const PackedFields pk = pack_fields(f, steps);
  // Structure-of-arrays positions in Z-order, padded to a multiple of the SIMD width (8 lanes
  // of double on CPU devices, 1 elsewhere); padding points sit at the origin (on the sphere: at
  // the last point, which the sphere's normalisation keeps finite) and are discarded.
  // The Z-order puts close points in one work item, so the kernel visits only the cells of
  // centres near them (kFieldCut) whatever the caller's numbering.
  const int lanes = dev.description().kind == DeviceKind::cpu ? 8 : 1;
  const size_t n = static_cast<size_t>(x.rows());
  const size_t nv = (n + lanes - 1) / lanes, np = nv * lanes;
  const std::vector<int> order = spatial_order(x);
  std::vector<double> soa(3 * np, 0.0);
  for (size_t i = 0; i < np; ++i)
    if (i < n || kind == 2)
      for (int c = 0; c < 3; ++c) soa[c * np + i] = x(order[std::min(i, n - 1)], c);
  auto& q = dev.cl().queue;
  bc::vector<double> dxs(soa.begin(), soa.begin() + np, q);
  bc::vector<double> dys(soa.begin() + np, soa.begin() + 2 * np, q);
  bc::vector<double> dzs(soa.begin() + 2 * np, soa.end(), q);
  bc::vector<int> dslot(pk.slot.begin(), pk.slot.end(), q);
  bc::vector<int> dcells(pk.cells.begin(), pk.cells.end(), q);
  bc::vector<double> dc(pk.centres.begin(), pk.centres.end(), q);
  bc::vector<double> da(pk.coefs.begin(), pk.coefs.end(), q);
  auto k = dev.cl().kernel("register", "rk4_advect_soa", "-DLANES=" + std::to_string(lanes));
  k.set_args(static_cast<int>(nv), dxs, dys, dzs, steps, 1.0 / steps, dslot, dcells, pk.origin(0), pk.origin(1),
             pk.origin(2), pk.side, pk.g, pk.reach, dc, da, f[0].lambda, kFieldCut, kind);
  dev.cl().launch(k, nv);
  bc::copy(dxs.begin(), dxs.end(), soa.begin(), q);
  bc::copy(dys.begin(), dys.end(), soa.begin() + np, q);
  bc::copy(dzs.begin(), dzs.end(), soa.begin() + 2 * np, q);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) x(order[i], c) = soa[c * np + i];
}

void check_fields(const std::vector<DivFreeField>& f, int steps) {
  if (steps < 1) throw InputError("advect: steps must be at least 1");
  if (f.size() != 1 && f.size() != static_cast<size_t>(2 * steps + 1))
    throw InputError("advect: expected 1 or 2K+1 fields");
}

void advect_kind(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps, int kind) {
  check_fields(f, steps);
  if (x.rows() == 0) return;
  if (dev.is_host()) return advect_host(x, f, steps, kind);
  advect_device(dev, x, f, steps, kind);
}

}  // namespace

void advect(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps) {
  advect_kind(dev, x, f, steps, f.empty() || f[0].kernel != RbfKernel::Tangent ? 0 : 1);
}

namespace detail {

void advect_on_sphere(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps) {
  advect_kind(dev, x, f, steps, 2);
}

void advect_in_disk(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps) {
  advect_kind(dev, x, f, steps, 3);
}

}  // namespace detail

}  // namespace vpm
