// ---- advection: K RK4 steps through the fields, on the host or the device ----
#include <boost/compute/container/vector.hpp>

#include "register/registration_steps.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/mesh_order.hpp"

namespace vpm {

namespace bc = boost::compute;

namespace {

void advect_host(Points& x, const std::vector<DivFreeField>& f, int steps) {
  const double dt = 1.0 / steps;
  auto field = [&](int s) -> const DivFreeField& { return f.size() == 1 ? f[0] : f[static_cast<size_t>(s)]; };
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    Eigen::Vector3d p = x.row(i).transpose();
    for (int k = 0; k < steps; ++k) {
      const Eigen::Vector3d k1 = field(2 * k)(p);
      const Eigen::Vector3d k2 = field(2 * k + 1)(p + 0.5 * dt * k1);
      const Eigen::Vector3d k3 = field(2 * k + 1)(p + 0.5 * dt * k2);
      const Eigen::Vector3d k4 = field(2 * k + 2)(p + dt * k3);
      p += dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    x.row(i) = p.transpose();
  }
}

/// The distinct fields packed for the kernel: all centres and coefficients one after the
/// other, and the (begin, end) centre range of each of the 2K + 1 stage slots.
struct PackedFields {
  std::vector<double> centres, coefs;
  std::vector<int> slot;
};

PackedFields pack_fields(const std::vector<DivFreeField>& f, int steps) {
  PackedFields pk;
  std::vector<int> range;
  for (const auto& field : f) {
    const int b = static_cast<int>(pk.centres.size() / 3);
    pk.centres.insert(pk.centres.end(), field.centres.data(), field.centres.data() + field.centres.size());
    pk.coefs.insert(pk.coefs.end(), field.coefficients.data(),
                    field.coefficients.data() + field.coefficients.size());
    range.push_back(b);
    range.push_back(static_cast<int>(pk.centres.size() / 3));
  }
  for (int s = 0; s <= 2 * steps; ++s) {
    const size_t fi = f.size() == 1 ? 0 : static_cast<size_t>(s);
    pk.slot.push_back(range[2 * fi]);
    pk.slot.push_back(range[2 * fi + 1]);
  }
  if (pk.centres.empty()) {
    pk.centres.assign(3, 0.0);
    pk.coefs.assign(3, 0.0);
  }
  return pk;
}

void advect_device(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps) {
  const PackedFields pk = pack_fields(f, steps);
  // Structure-of-arrays positions in Z-order, padded to a multiple of the SIMD width (8 lanes
  // of double on CPU devices, 1 elsewhere); padding points sit at the origin and are discarded.
  // The Z-order puts close points in one work item, so the kernel skips the centres far from
  // all of them (FIELD_CUT) whatever the caller's numbering.
  const int lanes = dev.description().kind == DeviceKind::cpu ? 8 : 1;
  const size_t n = static_cast<size_t>(x.rows());
  const size_t nv = (n + lanes - 1) / lanes, np = nv * lanes;
  const std::vector<int> order = spatial_order(x);
  std::vector<double> soa(3 * np, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) soa[c * np + i] = x(order[i], c);
  auto& q = dev.queue();
  bc::vector<double> dxs(soa.begin(), soa.begin() + np, q);
  bc::vector<double> dys(soa.begin() + np, soa.begin() + 2 * np, q);
  bc::vector<double> dzs(soa.begin() + 2 * np, soa.end(), q);
  bc::vector<int> dslot(pk.slot.begin(), pk.slot.end(), q);
  bc::vector<double> dc(pk.centres.begin(), pk.centres.end(), q);
  bc::vector<double> da(pk.coefs.begin(), pk.coefs.end(), q);
  auto k = dev.kernel("register", "rk4_advect_soa", "-DLANES=" + std::to_string(lanes));
  k.set_args(static_cast<int>(nv), dxs, dys, dzs, steps, 1.0 / steps, dslot, dc, da, f[0].lambda,
             f[0].kernel == RbfKernel::Tangent ? 1 : 0);
  dev.launch(k, nv);
  bc::copy(dxs.begin(), dxs.end(), soa.begin(), q);
  bc::copy(dys.begin(), dys.end(), soa.begin() + np, q);
  bc::copy(dzs.begin(), dzs.end(), soa.begin() + 2 * np, q);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) x(order[i], c) = soa[c * np + i];
}

}  // namespace

void advect(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps) {
  if (steps < 1) throw InputError("advect: steps must be at least 1");
  if (f.size() != 1 && f.size() != static_cast<size_t>(2 * steps + 1))
    throw InputError("advect: expected 1 or 2K+1 fields");
  if (x.rows() == 0) return;
  if (dev.is_host()) return advect_host(x, f, steps);
  advect_device(dev, x, f, steps);
}

}  // namespace vpm
