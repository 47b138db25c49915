#include "moser_field.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <boost/compute/algorithm/copy.hpp>
#include <boost/compute/container/vector.hpp>
#include <cmath>
#include <unordered_map>

#include "vpm/device.hpp"

namespace vpm::detail {

namespace bc = boost::compute;

std::vector<int> tet_neighbors(const Tets& tets) {
  const int m = static_cast<int>(tets.rows());
  std::vector<int> nbr(4 * static_cast<size_t>(m), -1);
  struct Face {
    std::array<int, 3> v;
    int slot;
  };
  std::vector<Face> faces;
  faces.reserve(4 * static_cast<size_t>(m));
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) {
      std::array<int, 3> f;
      int j = 0;
      for (int c = 0; c < 4; ++c)
        if (c != k) f[j++] = tets(t, c);
      std::sort(f.begin(), f.end());
      faces.push_back({f, 4 * t + k});
    }
  std::sort(faces.begin(), faces.end(), [](const Face& a, const Face& b) {
    return a.v != b.v ? a.v < b.v : a.slot < b.slot;
  });
  for (size_t i = 0; i + 1 < faces.size(); ++i)
    if (faces[i].v == faces[i + 1].v) {
      nbr[faces[i].slot] = faces[i + 1].slot / 4;
      nbr[faces[i + 1].slot] = faces[i].slot / 4;
      ++i;
    }
  return nbr;
}

void build_background(MoserField& f, const Points& x, const Tets& tets, const std::vector<int>& nbr) {
  f.n = static_cast<int>(x.rows());
  f.m = static_cast<int>(tets.rows());
  f.tets = &tets;
  f.nbr = &nbr;
  f.inv.assign(12 * static_cast<size_t>(f.m), 0.0);
  for (int t = 0; t < f.m; ++t) {
    const Eigen::Vector3d a = x.row(tets(t, 0)).transpose();
    Eigen::Matrix3d M;
    for (int c = 0; c < 3; ++c) M.col(c) = x.row(tets(t, c + 1)).transpose() - a;
    const Eigen::Matrix3d Mi = M.inverse();
    double* q = &f.inv[12 * static_cast<size_t>(t)];
    q[0] = a.x();
    q[1] = a.y();
    q[2] = a.z();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) q[3 + 3 * r + c] = Mi(r, c);
  }
  // Uniform grid: about one cell per tet over the bounding box (cells capped at 128 a side);
  // each tet is listed in every cell its bounding box (grown by a quarter cell) overlaps.
  Eigen::RowVector3d lo = x.colwise().minCoeff(), hi = x.colwise().maxCoeff();
  const Eigen::RowVector3d ext = (hi - lo).cwiseMax(1e-300);
  double h = std::cbrt(ext.prod() / std::max(1, f.m));
  for (int c = 0; c < 3; ++c) h = std::max(h, ext(c) / 128.0);
  lo.array() -= 0.5 * h;
  for (int c = 0; c < 3; ++c) {
    f.lo[c] = lo(c);
    f.dims[c] = std::max(1, static_cast<int>(std::ceil((ext(c) + h) / h)));
  }
  f.inv_h = 1.0 / h;
  const int gx = f.dims[0], gy = f.dims[1], gz = f.dims[2];
  const size_t cells = static_cast<size_t>(gx) * gy * gz;
  auto cell_range = [&](int t, int* a, int* b) {
    for (int c = 0; c < 3; ++c) {
      double mn = 1e300, mx = -1e300;
      for (int k = 0; k < 4; ++k) {
        mn = std::min(mn, x(tets(t, k), c));
        mx = std::max(mx, x(tets(t, k), c));
      }
      a[c] = std::clamp(static_cast<int>(std::floor((mn - 0.25 * h - f.lo[c]) * f.inv_h)), 0, f.dims[c] - 1);
      b[c] = std::clamp(static_cast<int>(std::floor((mx + 0.25 * h - f.lo[c]) * f.inv_h)), 0, f.dims[c] - 1);
    }
  };
  f.cell_start.assign(cells + 1, 0);
  int a[3], b[3];
  for (int t = 0; t < f.m; ++t) {
    cell_range(t, a, b);
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int i = a[0]; i <= b[0]; ++i) ++f.cell_start[1 + i + gx * (j + static_cast<size_t>(gy) * k)];
  }
  for (size_t c = 0; c < cells; ++c) f.cell_start[c + 1] += f.cell_start[c];
  f.cell_tets.assign(static_cast<size_t>(f.cell_start[cells]), 0);
  std::vector<int> fill(f.cell_start.begin(), f.cell_start.end() - 1);
  for (int t = 0; t < f.m; ++t) {
    cell_range(t, a, b);
    for (int k = a[2]; k <= b[2]; ++k)
      for (int j = a[1]; j <= b[1]; ++j)
        for (int i = a[0]; i <= b[0]; ++i) f.cell_tets[fill[i + gx * (j + static_cast<size_t>(gy) * k)]++] = t;
  }
}

Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> tet_gradients(const MoserField& f,
                                                                       const Eigen::VectorXd& psi) {
  Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor> g(f.m, 3);
  const Tets& T = *f.tets;
  for (int t = 0; t < f.m; ++t) {
    const double* q = &f.inv[12 * static_cast<size_t>(t)];
    const double d1 = psi(T(t, 1)) - psi(T(t, 0)), d2 = psi(T(t, 2)) - psi(T(t, 0)),
                 d3 = psi(T(t, 3)) - psi(T(t, 0));
    // grad psi = sum_j (psi_j - psi_0) grad lambda_j, grad lambda_j = row j of Minv
    for (int c = 0; c < 3; ++c) g(t, c) = d1 * q[3 + c] + d2 * q[6 + c] + d3 * q[9 + c];
  }
  return g;
}

// ---- host reference (mirrors kernels/moser.cl) ---------------------------------------------

namespace {
constexpr int kMaxWalk = 64;
constexpr double kInsideEps = -1e-12;
constexpr double kOutsideClamp = -0.05;
}  // namespace

void bary(const MoserField& f, int t, const Eigen::Vector3d& p, double* l) {
  const double* q = &f.inv[12 * static_cast<size_t>(t)];
  const double dx = p.x() - q[0], dy = p.y() - q[1], dz = p.z() - q[2];
  l[1] = q[3] * dx + q[4] * dy + q[5] * dz;
  l[2] = q[6] * dx + q[7] * dy + q[8] * dz;
  l[3] = q[9] * dx + q[10] * dy + q[11] * dz;
  l[0] = 1.0 - l[1] - l[2] - l[3];
}

namespace {
inline double min4(const double* l) { return std::min(std::min(l[0], l[1]), std::min(l[2], l[3])); }

inline void clamp_bary(double* l) {
  double s = 0;
  for (int k = 0; k < 4; ++k) {
    l[k] = std::max(l[k], 0.0);
    s += l[k];
  }
  for (int k = 0; k < 4; ++k) l[k] = s <= 0 ? 0.25 : l[k] / s;
}

}  // namespace

int locate(const MoserField& f, const Eigen::Vector3d& p, int t, double* l, long long* st) {
  const std::vector<int>& nbr = *f.nbr;
  for (int s = 0; s < kMaxWalk; ++s) {
    bary(f, t, p, l);
    int k = 0;
    for (int c = 1; c < 4; ++c)
      if (l[c] < l[k]) k = c;
    if (l[k] >= kInsideEps) return t;
    const int nb = nbr[4 * static_cast<size_t>(t) + k];
    if (nb < 0) {
      if (l[k] > kOutsideClamp) {
        clamp_bary(l);
        st[2] += 1;
        return t;
      }
      break;
    }
    t = nb;
    st[0] += 1;
  }
  st[1] += 1;
  int idx[3];
  for (int c = 0; c < 3; ++c)
    idx[c] = std::clamp(static_cast<int>(std::floor((p(c) - f.lo[c]) * f.inv_h)), 0, f.dims[c] - 1);
  const size_t cell = idx[0] + f.dims[0] * (idx[1] + static_cast<size_t>(f.dims[1]) * idx[2]);
  int best = -1;
  double best_score = -1e300, lb[4];
  for (int j = f.cell_start[cell]; j < f.cell_start[cell + 1]; ++j) {
    const int c = f.cell_tets[j];
    bary(f, c, p, lb);
    const double sc = min4(lb);
    if (sc > best_score) {
      best_score = sc;
      best = c;
    }
  }
  if (best < 0) best = t;
  bary(f, best, p, l);
  if (min4(l) < kInsideEps) {
    clamp_bary(l);
    st[2] += 1;
  }
  return best;
}

namespace {

// Velocity of point i at position x_i + c k_i, time t (boundary: renormalised, tangential).
Eigen::Vector3d velocity(const MoserField& f, bool on_b, bool slide, Eigen::Vector3d p, double t,
                         int& hint, long long* st) {
  if (on_b && !slide) return Eigen::Vector3d::Zero();
  if (on_b) p /= p.norm();
  double l[4];
  const int tet = locate(f, p, hint, l, st);
  hint = tet;
  const Tets& T = *f.tets;
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  double r = 0;
  for (int k = 0; k < 4; ++k) {
    const int v = T(tet, k);
    g += l[k] * Eigen::Vector3d(f.grad[3 * v], f.grad[3 * v + 1], f.grad[3 * v + 2]);
    r += l[k] * f.rho0[v];
  }
  Eigen::Vector3d u = g / ((1.0 - t) * r + t);
  if (on_b) u -= u.dot(p) * p;
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
      xi += (dt / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      if (on_b) xi /= xi.norm();
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

// ---- OpenCL ------------------------------------------------------------------------------

struct DeviceAdvector::Impl {
  Device& dev;
  int n, m;
  bc::kernel kvel, kupd;
  bc::vector<int> tets, nbr, hint, cell_start, cell_tets, stats;
  bc::vector<char> boundary;
  bc::vector<double> inv, grad, rho0, x, k1, k2, k3, k4;
  double lo[3] = {0, 0, 0}, inv_h = 1;
  int dims[3] = {1, 1, 1};
  std::vector<char> bmask;

  Impl(Device& d, const Tets& T, const std::vector<int>& nb, const std::vector<char>& b)
      : dev(d),
        n(static_cast<int>(b.size())),
        m(static_cast<int>(T.rows())),
        kvel(d.kernel("moser", "moser_velocity")),
        kupd(d.kernel("moser", "moser_rk_update")),
        tets(T.data(), T.data() + T.size(), d.queue()),
        nbr(nb.begin(), nb.end(), d.queue()),
        hint(static_cast<size_t>(n), d.context()),
        cell_start(d.context()),
        cell_tets(d.context()),
        stats(3 * static_cast<size_t>(n), d.context()),
        boundary(b.begin(), b.end(), d.queue()),
        inv(d.context()),
        grad(3 * static_cast<size_t>(n), d.context()),
        rho0(static_cast<size_t>(n), d.context()),
        x(3 * static_cast<size_t>(n), d.context()),
        k1(3 * static_cast<size_t>(n), d.context()),
        k2(3 * static_cast<size_t>(n), d.context()),
        k3(3 * static_cast<size_t>(n), d.context()),
        k4(3 * static_cast<size_t>(n), d.context()),
        bmask(b) {}
};

DeviceAdvector::DeviceAdvector(Device& device, const Tets& tets, const std::vector<int>& nbr,
                               const std::vector<char>& boundary)
    : impl_(std::make_unique<Impl>(device, tets, nbr, boundary)) {}

DeviceAdvector::~DeviceAdvector() = default;

void DeviceAdvector::set_field(const MoserField& f) {
  Impl& s = *impl_;
  auto& q = s.dev.queue();
  s.inv = bc::vector<double>(f.inv.begin(), f.inv.end(), q);
  bc::copy(f.grad.begin(), f.grad.end(), s.grad.begin(), q);
  bc::copy(f.rho0.begin(), f.rho0.end(), s.rho0.begin(), q);
  s.cell_start = bc::vector<int>(f.cell_start.begin(), f.cell_start.end(), q);
  if (f.cell_tets.empty()) {
    const int zero = 0;
    s.cell_tets = bc::vector<int>(&zero, &zero + 1, q);
  } else {
    s.cell_tets = bc::vector<int>(f.cell_tets.begin(), f.cell_tets.end(), q);
  }
  for (int c = 0; c < 3; ++c) {
    s.lo[c] = f.lo[c];
    s.dims[c] = f.dims[c];
  }
  s.inv_h = f.inv_h;
}

void DeviceAdvector::advect(const AdvectParams& prm, Points& x, std::vector<int>& hint,
                            AdvectStats* stats) {
  Impl& s = *impl_;
  auto& q = s.dev.queue();
  bc::copy(x.data(), x.data() + x.size(), s.x.begin(), q);
  bc::copy(hint.begin(), hint.end(), s.hint.begin(), q);
  std::vector<int> zeros(3 * static_cast<size_t>(s.n), 0);
  bc::copy(zeros.begin(), zeros.end(), s.stats.begin(), q);
  const std::vector<double> zd(3 * static_cast<size_t>(s.n), 0.0);
  bc::copy(zd.begin(), zd.end(), s.k4.begin(), q);
  const double dt = prm.t_end / prm.steps;
  auto& kv = s.kvel;
  kv.set_arg(0, s.n);
  kv.set_arg(1, s.x);
  kv.set_arg(5, static_cast<int>(prm.slide));
  kv.set_arg(6, s.boundary);
  kv.set_arg(7, s.hint);
  kv.set_arg(8, s.inv);
  kv.set_arg(9, s.tets);
  kv.set_arg(10, s.nbr);
  kv.set_arg(11, s.grad);
  kv.set_arg(12, s.rho0);
  kv.set_arg(13, s.lo[0]);
  kv.set_arg(14, s.lo[1]);
  kv.set_arg(15, s.lo[2]);
  kv.set_arg(16, s.inv_h);
  kv.set_arg(17, s.dims[0]);
  kv.set_arg(18, s.dims[1]);
  kv.set_arg(19, s.dims[2]);
  kv.set_arg(20, s.cell_start);
  kv.set_arg(21, s.cell_tets);
  kv.set_arg(23, s.stats);
  auto& ku = s.kupd;
  ku.set_arg(0, s.n);
  ku.set_arg(1, s.x);
  ku.set_arg(2, s.k1);
  ku.set_arg(3, s.k2);
  ku.set_arg(4, s.k3);
  ku.set_arg(5, s.k4);
  ku.set_arg(6, dt);
  ku.set_arg(7, static_cast<int>(prm.slide));
  ku.set_arg(8, s.boundary);
  auto stage = [&](bc::vector<double>& kin, double c, double t, bc::vector<double>& out) {
    kv.set_arg(2, kin);
    kv.set_arg(3, c);
    kv.set_arg(4, t);
    kv.set_arg(22, out);
    s.dev.launch(kv, static_cast<size_t>(s.n));
  };
  for (int st = 0; st < prm.steps; ++st) {
    const double t0 = st * dt;
    stage(s.k4, 0.0, t0, s.k1);  // c = 0: kin (finite, last step's k4) is not used
    stage(s.k1, 0.5 * dt, t0 + 0.5 * dt, s.k2);
    stage(s.k2, 0.5 * dt, t0 + 0.5 * dt, s.k3);
    stage(s.k3, dt, t0 + dt, s.k4);
    s.dev.launch(ku, static_cast<size_t>(s.n));
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
