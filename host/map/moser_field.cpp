#include "map/moser_field.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <boost/compute/algorithm/copy.hpp>
#include <boost/compute/container/vector.hpp>
#include <cmath>
#include <stdexcept>
#include <unordered_map>

#include "core/parallel.hpp"
#include "core/device_cl.hpp"
#include "mesh/tet_geometry.hpp"
#include "vpm/device.hpp"
#include "vpm/topology.hpp"

namespace vpm::detail {

namespace bc = boost::compute;

// the field's expressions, shared with kernels/moser.cl (after tet_geometry's products)
#include "kernels/moser_field.clh"


Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> tet_gradients(const MoserField& f,
                                                                       const Eigen::VectorXd& psi) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> g(f.m, 3);
  const Tets& T = *f.tets;
  parallel_for(f.m, 8192, [&](int t0, int t1) {
    for (int t = t0; t < t1; ++t) {
      const double* q = &f.inv[12 * static_cast<size_t>(t)];
      mf_tet_gradient(q, psi(T(t, 1)) - psi(T(t, 0)), psi(T(t, 2)) - psi(T(t, 0)), psi(T(t, 3)) - psi(T(t, 0)),
                      &g(t, 0));
    }
  });
  return g;
}

std::vector<double> vertex_gradients(const Tets& tets, const Points& x,
                                     const Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>& G,
                                     const Eigen::VectorXd& vol, const std::vector<char>& boundary,
                                     bool slide) {
  const int n = static_cast<int>(x.rows()), m = static_cast<int>(tets.rows());
  std::vector<double> g(3 * static_cast<size_t>(n), 0.0), w(static_cast<size_t>(n), 0.0);
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) {
      const int v = tets(t, k);
      w[v] += vol(t);
      for (int d = 0; d < 3; ++d) g[3 * v + d] += vol(t) * G(t, d);
    }
  for (int v = 0; v < n; ++v) {
    double* gv = &g[3 * static_cast<size_t>(v)];
    if (w[v] > 0)
      for (int d = 0; d < 3; ++d) gv[d] /= w[v];
    const double p[3] = {x(v, 0), x(v, 1), x(v, 2)};
    mf_boundary_gradient(boundary[v], slide, p, gv);
  }
  return g;
}

namespace {

// Velocity of point i at position x_i + c k_i, time t (boundary: renormalised, tangential).
Eigen::Vector3d velocity(const MoserField& f, bool on_b, bool slide, Eigen::Vector3d p, double t,
                         int& hint, long long* st) {
  if (on_b && !slide) return Eigen::Vector3d::Zero();
  if (on_b) mf_unit(p.data());
  double l[4];
  const int tet = locate(f, p, hint, l, st);
  hint = tet;
  Eigen::Vector3d u;
  mf_velocity(&(*f.tets)(tet, 0), l, f.grad.data(), f.rho0.data(), t, on_b, p.data(), u.data());
  return u;
}

}  // namespace

void advect_host(const MoserField& f, const std::vector<char>& boundary, const AdvectParams& prm,
                 Points& x, std::vector<int>& hint, AdvectStats* stats) {
  const int n = static_cast<int>(x.rows());
  const double dt = prm.t_end / prm.steps;
  long long st[3] = {0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const bool on_b = boundary[i] != 0;
    if (on_b && !prm.slide) continue;
    Eigen::Vector3d xi = x.row(i).transpose();
    int h = hint[i];
    for (int s = 0; s < prm.steps; ++s) {
      const double t0 = s * dt;
      const Eigen::Vector3d k1 = velocity(f, on_b, prm.slide, xi, t0, h, st);
      const Eigen::Vector3d k2 = velocity(f, on_b, prm.slide, xi + 0.5 * dt * k1, t0 + 0.5 * dt, h, st);
      const Eigen::Vector3d k3 = velocity(f, on_b, prm.slide, xi + 0.5 * dt * k2, t0 + 0.5 * dt, h, st);
      const Eigen::Vector3d k4 = velocity(f, on_b, prm.slide, xi + dt * k3, t0 + dt, h, st);
      mf_rk4_step(xi.data(), k1.data(), k2.data(), k3.data(), k4.data(), dt, on_b);
    }
    x.row(i) = xi.transpose();
    hint[i] = h;
  }
  if (stats) {
    long long moving = 0;
    for (int i = 0; i < n; ++i) moving += !(boundary[i] && !prm.slide);
    stats->locations += 4LL * prm.steps * moving;
    stats->walk_steps += st[0];
    stats->grid_fallbacks += st[1];
    stats->clamped += st[2];
  }
}

void HostAdvector::advect(const AdvectParams& p, Points& x, std::vector<int>& hint, AdvectStats* stats) {
  if (!field_) throw std::logic_error("HostAdvector::advect: no field (set_field first)");
  advect_host(*field_, boundary_, p, x, hint, stats);
}

// ---- OpenCL ------------------------------------------------------------------------------

struct DeviceAdvector::Impl {
  Device& dev;
  int n, m;
  bc::kernel kvel, kupd;
  bc::vector<int> tets, nbr, hint, cell_start, stats;
  bc::vector<char> boundary;
  bc::vector<double> grad, rho0, x, k1, k2, k3, k4;
  // the background's two big arrays: on CPU devices views of the host's (no copy), else copies
  bc::buffer inv, cell_tets;
  bool zero_copy = false, inv_is_view = false;
  double lo[3] = {0, 0, 0}, inv_h = 1;
  int dims[3] = {1, 1, 1};
  std::vector<char> bmask;
  // the field from psi on the device (set_field with psi): built at its first use
  bc::kernel kvg;
  bc::vector<int> inc_offset, inc_tet;
  bc::vector<double> psi;

  Impl(Device& d, const Tets& T, const std::vector<int>& nb, const std::vector<char>& b)
      : dev(d),
        n(static_cast<int>(b.size())),
        m(static_cast<int>(T.rows())),
        kvel(d.cl().kernel("moser", "moser_velocity")),
        kupd(d.cl().kernel("moser", "moser_rk_update")),
        tets(T.data(), T.data() + T.size(), d.cl().queue),
        nbr(nb.begin(), nb.end(), d.cl().queue),
        hint(static_cast<size_t>(n), d.cl().context),
        cell_start(d.cl().context),
        stats(3 * static_cast<size_t>(n), d.cl().context),
        boundary(b.begin(), b.end(), d.cl().queue),
        grad(3 * static_cast<size_t>(n), d.cl().context),
        rho0(static_cast<size_t>(n), d.cl().context),
        x(3 * static_cast<size_t>(n), d.cl().context),
        k1(3 * static_cast<size_t>(n), d.cl().context),
        k2(3 * static_cast<size_t>(n), d.cl().context),
        k3(3 * static_cast<size_t>(n), d.cl().context),
        k4(3 * static_cast<size_t>(n), d.cl().context),
        bmask(b),
        inc_offset(d.cl().context),
        inc_tet(d.cl().context),
        psi(d.cl().context),
        zero_copy(d.description().kind == DeviceKind::cpu) {}

  bc::kernel kinv;  // the inverse matrices from x on the device (set_field with psi)

  // The background of a round without its gradients; f.inv is uploaded unless
  // `inverses_here` (then the caller makes them on the device).
  void upload_background(const MoserField& f, bool inverses_here = false);

  // A read-only buffer of `bytes` at host memory p: a view of it on CPU devices (valid while p
  // lives unchanged: DeviceAdvector::release_field), a copy elsewhere.
  bc::buffer host_array(const void* p, size_t bytes, bool view) {
    const cl_mem_flags how = view && zero_copy ? CL_MEM_USE_HOST_PTR : CL_MEM_COPY_HOST_PTR;
    return bc::buffer(dev.cl().context, bytes, CL_MEM_READ_ONLY | how, const_cast<void*>(p));
  }
};

DeviceAdvector::DeviceAdvector(Device& device, const Tets& tets, const std::vector<int>& nbr,
                               const std::vector<char>& boundary)
    : impl_(std::make_unique<Impl>(device, tets, nbr, boundary)) {}

DeviceAdvector::~DeviceAdvector() = default;

void DeviceAdvector::set_field(const MoserField& f) {
  Impl& s = *impl_;
  s.upload_background(f);
  bc::copy(f.grad.begin(), f.grad.end(), s.grad.begin(), s.dev.cl().queue);
}

void DeviceAdvector::set_field(const MoserField& f, const Eigen::VectorXd& psi, const Points& x,
                               bool slide) {
  Impl& s = *impl_;
  auto& q = s.dev.cl().queue;
  s.upload_background(f, true);
  if (s.inc_offset.size() != static_cast<size_t>(s.n) + 1) {
    const Incidence inc = vertex_tet_incidence(s.n, *f.tets);
    s.inc_offset = bc::vector<int>(inc.offset.begin(), inc.offset.end(), q);
    s.inc_tet = bc::vector<int>(inc.tet_of.begin(), inc.tet_of.end(), q);
    s.psi = bc::vector<double>(static_cast<size_t>(s.n), s.dev.cl().context);
    s.kvg = s.dev.cl().kernel("moser", "moser_vertex_gradients");
    s.kinv = s.dev.cl().kernel("moser", "moser_tet_inverses");
  }
  bc::copy(psi.data(), psi.data() + psi.size(), s.psi.begin(), q);
  bc::copy(x.data(), x.data() + x.size(), s.x.begin(), q);
  const size_t inv_bytes = 12 * sizeof(double) * static_cast<size_t>(std::max(1, s.m));
  if (s.inv.get() == nullptr || s.inv.size() != inv_bytes || s.inv_is_view) {
    s.inv = bc::buffer(s.dev.cl().context, inv_bytes);
    s.inv_is_view = false;
  }
  s.kinv.set_args(s.m, s.x, s.tets, s.inv);
  s.dev.cl().launch(s.kinv, static_cast<size_t>(s.m));
  s.kvg.set_args(s.n, s.inc_offset, s.inc_tet, s.tets, s.inv, s.psi, s.boundary, static_cast<int>(slide),
                 s.x, s.grad);
  s.dev.cl().launch(s.kvg, static_cast<size_t>(s.n));
}

std::vector<double> DeviceAdvector::gradients() {
  Impl& s = *impl_;
  std::vector<double> g(s.grad.size());
  bc::copy(s.grad.begin(), s.grad.end(), g.begin(), s.dev.cl().queue);
  return g;
}

void DeviceAdvector::release_field() {
  Impl& s = *impl_;
  s.cell_tets = bc::buffer();
  if (s.inv_is_view) {
    s.inv = bc::buffer();
    s.inv_is_view = false;
  }
}

std::vector<double> DeviceAdvector::inverses() {
  Impl& s = *impl_;
  std::vector<double> v(12 * static_cast<size_t>(s.m));
  if (!v.empty()) s.dev.cl().queue.enqueue_read_buffer(s.inv, 0, v.size() * sizeof(double), v.data());
  return v;
}

void DeviceAdvector::Impl::upload_background(const MoserField& f, bool inverses_here) {
  Impl& s = *this;
  auto& q = s.dev.cl().queue;
  // the last round's buffers go first: the new ones are not made beside them (12 doubles a tet)
  s.cell_tets = bc::buffer();
  static const double no_tet[12] = {};
  static const int no_cell = 0;
  if (!inverses_here) {
    s.inv = bc::buffer();
    s.inv = f.inv.empty() ? s.host_array(no_tet, sizeof(no_tet), false)
                          : s.host_array(f.inv.data(), f.inv.size() * sizeof(double), true);
    s.inv_is_view = s.zero_copy && !f.inv.empty();
  }
  bc::copy(f.rho0.begin(), f.rho0.end(), s.rho0.begin(), q);
  s.cell_start = bc::vector<int>(f.cell_start.begin(), f.cell_start.end(), q);
  s.cell_tets = f.cell_tets.empty() ? s.host_array(&no_cell, sizeof(int), false)
                                    : s.host_array(f.cell_tets.data(), f.cell_tets.size() * sizeof(int), true);
  for (int c = 0; c < 3; ++c) {
    s.lo[c] = f.lo[c];
    s.dims[c] = f.dims[c];
  }
  s.inv_h = f.inv_h;
}

void DeviceAdvector::advect(const AdvectParams& prm, Points& x, std::vector<int>& hint,
                            AdvectStats* stats) {
  Impl& s = *impl_;
  auto& q = s.dev.cl().queue;
  bc::copy(x.data(), x.data() + x.size(), s.x.begin(), q);
  bc::copy(hint.begin(), hint.end(), s.hint.begin(), q);
  std::vector<int> zeros(3 * static_cast<size_t>(s.n), 0);
  bc::copy(zeros.begin(), zeros.end(), s.stats.begin(), q);
  const std::vector<double> zd(3 * static_cast<size_t>(s.n), 0.0);
  bc::copy(zd.begin(), zd.end(), s.k4.begin(), q);
  const double dt = prm.t_end / prm.steps;
  auto& kv = s.kvel;
  kv.set_args(s.n, s.x);
  set_args_at(kv, 5, static_cast<int>(prm.slide), s.boundary, s.hint, s.inv, s.tets, s.nbr, s.grad,
                     s.rho0, s.lo[0], s.lo[1], s.lo[2], s.inv_h, s.dims[0], s.dims[1], s.dims[2],
                     s.cell_start, s.cell_tets);
  kv.set_arg(23, s.stats);
  auto& ku = s.kupd;
  ku.set_args(s.n, s.x, s.k1, s.k2, s.k3, s.k4, dt, static_cast<int>(prm.slide), s.boundary);
  auto stage = [&](bc::vector<double>& kin, double c, double t, bc::vector<double>& out) {
    set_args_at(kv, 2, kin, c, t);
    kv.set_arg(22, out);
    s.dev.cl().launch(kv, static_cast<size_t>(s.n));
  };
  for (int st = 0; st < prm.steps; ++st) {
    const double t0 = st * dt;
    stage(s.k4, 0.0, t0, s.k1);  // c = 0: kin (finite, last step's k4) is not used
    stage(s.k1, 0.5 * dt, t0 + 0.5 * dt, s.k2);
    stage(s.k2, 0.5 * dt, t0 + 0.5 * dt, s.k3);
    stage(s.k3, dt, t0 + dt, s.k4);
    s.dev.cl().launch(ku, static_cast<size_t>(s.n));
  }
  bc::copy(s.x.begin(), s.x.end(), x.data(), q);
  bc::copy(s.hint.begin(), s.hint.end(), hint.begin(), q);
  if (stats) {
    std::vector<int> h(3 * static_cast<size_t>(s.n));
    bc::copy(s.stats.begin(), s.stats.end(), h.begin(), q);
    long long moving = 0;
    for (int i = 0; i < s.n; ++i) {
      moving += !(s.bmask[i] && !prm.slide);
      stats->walk_steps += h[3 * i];
      stats->grid_fallbacks += h[3 * i + 1];
      stats->clamped += h[3 * i + 2];
    }
    stats->locations += 4LL * prm.steps * moving;
  }
}

}  // namespace vpm::detail
