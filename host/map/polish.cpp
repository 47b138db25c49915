#include "map/polish.hpp"

#include <Eigen/Dense>
#include <boost/compute/algorithm/copy.hpp>
#include <boost/compute/algorithm/fill.hpp>
#include <boost/compute/container/vector.hpp>
#include <cmath>

#include "core/parallel.hpp"
#include "vpm/device.hpp"
#include "vpm/geometry.hpp"

namespace vpm::detail {

namespace bc = boost::compute;

std::vector<char> polish_freedom(const std::vector<char>& boundary, bool slide, const std::vector<char>& pinned) {
  std::vector<char> f(boundary.size(), kPolishFree);
  for (size_t v = 0; v < boundary.size(); ++v) {
    if (!pinned.empty() && pinned[v]) f[v] = kPolishFixed;
    else if (boundary[v]) f[v] = slide ? kPolishTangent : kPolishFixed;
  }
  return f;
}

PolishDirection polish_direction_host(const Points& x, const Tets& tets, const Eigen::VectorXd& target,
                                      const std::vector<char>& freedom, int iterations) {
  const int n = static_cast<int>(x.rows()), m = static_cast<int>(tets.rows());
  const Eigen::VectorXd vol = tet_volumes(x, tets);
  // per-tet scaled gradients sg_{t,k} = vol_t grad phi_k / target_t
  std::vector<Eigen::Vector3d> sg(4 * static_cast<size_t>(m));
  Eigen::VectorXd b(m);
  parallel_for(m, 8192, [&](int t0, int t1) {
    for (int t = t0; t < t1; ++t) {
      const Eigen::Vector3d a = x.row(tets(t, 0)).transpose();
      Eigen::Matrix3d M;
      for (int q = 0; q < 3; ++q) M.col(q) = x.row(tets(t, q + 1)).transpose() - a;
      const Eigen::Matrix3d Mi = M.inverse();
      const double s = vol(t) / target(t);
      Eigen::Vector3d g0 = Eigen::Vector3d::Zero();
      for (int q = 0; q < 3; ++q) {
        sg[4 * t + q + 1] = s * Mi.row(q).transpose();
        g0 -= sg[4 * t + q + 1];
      }
      sg[4 * t] = g0;
      b(t) = 1.0 - vol(t) / target(t);
    }
  });
  auto project = [&](Points& d) {
    for (int v = 0; v < n; ++v) {
      if (freedom[v] == kPolishFixed) {
        d.row(v).setZero();
      } else if (freedom[v] == kPolishTangent) {
        const Eigen::Vector3d nv = x.row(v).transpose().normalized(), u = d.row(v).transpose();
        d.row(v) = (u - u.dot(nv) * nv).transpose();
      }
    }
  };
  auto apply = [&](const Points& d, Eigen::VectorXd& out) {  // out = A d (d already projected)
    parallel_for(m, 8192, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) {
        double s = 0;
        for (int k = 0; k < 4; ++k) s += sg[4 * t + k].dot(d.row(tets(t, k)).transpose());
        out(t) = s;
      }
    });
  };
  // out = P A^T y: tets split into two fixed chunks, each scattering into its own buffer (no
  // races, and the result does not depend on the number of threads), then summed.
  const int chunks = m >= 8192 ? 2 : 1;
  std::vector<Points> part(static_cast<size_t>(chunks));
  auto apply_t = [&](const Eigen::VectorXd& y, Points& out) {
    const int per = (m + chunks - 1) / chunks;
    parallel_for(chunks, 2, [&](int k0, int k1) {
      for (int j = k0; j < k1; ++j) {
        Points& o = part[static_cast<size_t>(j)];
        o.setZero(n, 3);
        for (int t = j * per; t < std::min(m, (j + 1) * per); ++t)
          for (int k = 0; k < 4; ++k) o.row(tets(t, k)) += y(t) * sg[4 * t + k].transpose();
      }
    });
    out = part[0];
    for (int j = 1; j < chunks; ++j) out += part[static_cast<size_t>(j)];
    project(out);
  };
  PolishDirection res;
  Points dx = Points::Zero(n, 3), s(n, 3), p(n, 3);
  Eigen::VectorXd rr = b, q(m);
  apply_t(rr, s);
  p = s;
  double gamma = s.squaredNorm();
  int it = 0;
  for (; it < iterations && gamma > 0; ++it) {
    apply(p, q);
    const double qq = q.squaredNorm();
    if (qq <= 0) break;
    const double alpha = gamma / qq;
    dx += alpha * p;
    rr -= alpha * q;
    apply_t(rr, s);
    const double g2 = s.squaredNorm();
    p = s + (g2 / gamma) * p;
    gamma = g2;
  }
  res.dx = std::move(dx);
  res.iterations = it;
  res.residual = b.norm() > 0 ? rr.norm() / b.norm() : 0;
  return res;
}

// ---- OpenCL ----------------------------------------------------------------------------------

namespace {
enum { P_OP_INIT = 0, P_OP_ALPHA = 1, P_OP_BETA = 2, P_OP_RR = 3 };
enum { P_ITER = 4, P_BB = 5, P_RR = 6, kPolishSlots = 8 };
}  // namespace

struct DevicePolisher::Impl {
  Device& dev;
  int n, m;
  size_t G;  // reduction grid
  bc::vector<int> tets, inc_ptr, inc_slot;
  bc::vector<char> freedom;
  bc::vector<double> x, target, sg, b, r, q, dx, p, s, partial, S;
  bc::kernel k_setup, k_apply, k_apply_t, k_scalars, k_update, k_update_p;
  Impl(Device& d, int n_, int m_)
      : dev(d), n(n_), m(m_), tets(d.context()), inc_ptr(d.context()), inc_slot(d.context()),
        freedom(d.context()), x(d.context()), target(d.context()), sg(d.context()), b(d.context()),
        r(d.context()), q(d.context()), dx(d.context()), p(d.context()), s(d.context()),
        partial(d.context()), S(d.context()) {}
  void scalars(int op) {
    k_scalars.set_arg(1, op);
    dev.launch(k_scalars, dev.combine_items());
  }
};

DevicePolisher::DevicePolisher(Device& dev, const Tets& tets, int n, const std::vector<char>& freedom) {
  const int m = static_cast<int>(tets.rows());
  impl_ = std::make_unique<Impl>(dev, n, m);
  Impl& I = *impl_;
  auto& queue = dev.queue();
  const bool cpu = dev.description().type == "cpu";
  const size_t ls = dev.local_size();
  const unsigned cu = std::max(1u, dev.description().compute_units);
  I.G = cpu ? ls * std::max<size_t>(4, 2 * cu) : ls * std::max<size_t>(64, 4 * cu);
  // vertex -> tet-corner slots (4 t + k), CSR
  std::vector<int> ptr(static_cast<size_t>(n) + 1, 0), slot(4 * static_cast<size_t>(m));
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) ++ptr[static_cast<size_t>(tets(t, k)) + 1];
  for (int v = 0; v < n; ++v) ptr[v + 1] += ptr[v];
  std::vector<int> fill(ptr.begin(), ptr.end() - 1);
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) slot[static_cast<size_t>(fill[tets(t, k)]++)] = 4 * t + k;
  I.tets = bc::vector<int>(tets.data(), tets.data() + 4 * static_cast<size_t>(m), queue);
  I.inc_ptr = bc::vector<int>(ptr.begin(), ptr.end(), queue);
  I.inc_slot = bc::vector<int>(slot.begin(), slot.end(), queue);
  I.freedom = bc::vector<char>(freedom.begin(), freedom.end(), queue);
  const size_t n3 = 3 * static_cast<size_t>(std::max(n, 1)), mm = static_cast<size_t>(std::max(m, 1));
  I.x = bc::vector<double>(n3, dev.context());
  I.target = bc::vector<double>(mm, dev.context());
  I.sg = bc::vector<double>(12 * mm, dev.context());
  I.b = bc::vector<double>(mm, dev.context());
  I.r = bc::vector<double>(mm, dev.context());
  I.q = bc::vector<double>(mm, dev.context());
  I.dx = bc::vector<double>(n3, dev.context());
  I.p = bc::vector<double>(n3, dev.context());
  I.s = bc::vector<double>(n3, dev.context());
  I.partial = bc::vector<double>(2 * I.G, dev.context());
  I.S = bc::vector<double>(kPolishSlots, dev.context());
  for (auto* v : {&I.x, &I.target, &I.sg, &I.b, &I.r, &I.q, &I.dx, &I.p, &I.s, &I.partial, &I.S})
    bc::fill(v->begin(), v->end(), 0.0, queue);

  I.k_setup = dev.kernel("polish", "polish_setup");
  I.k_setup.set_args(m, I.tets, I.x, I.target, I.sg, I.b, I.r);
  I.k_apply = dev.kernel("polish", "polish_apply");
  I.k_apply.set_args(m, I.tets, I.sg, I.p, I.q, I.partial);
  I.k_apply_t = dev.kernel("polish", "polish_apply_t");
  I.k_apply_t.set_args(n, m, I.inc_ptr, I.inc_slot, I.sg, I.r, I.freedom, I.x, I.s, I.partial);
  I.k_scalars = dev.kernel("polish", "polish_scalars");
  I.k_scalars.set_arg(0, static_cast<int>(dev.reduction_partials(I.G)));
  set_args_at(I.k_scalars, 2, I.partial, I.S);
  I.k_update = dev.kernel("polish", "polish_update");
  I.k_update.set_args(3 * n, m, I.S, I.dx, I.p, I.r, I.q);
  I.k_update_p = dev.kernel("polish", "polish_update_p");
  I.k_update_p.set_args(3 * n, I.S, I.p, I.s);
}

DevicePolisher::~DevicePolisher() = default;

PolishDirection DevicePolisher::direction(const Points& x, const Eigen::VectorXd& target, int iterations) {
  Impl& I = *impl_;
  auto& queue = I.dev.queue();
  PolishDirection res;
  res.dx = Points::Zero(I.n, 3);
  if (I.n == 0 || I.m == 0) return res;
  bc::copy(x.data(), x.data() + 3 * static_cast<size_t>(I.n), I.x.begin(), queue);
  bc::copy(target.data(), target.data() + I.m, I.target.begin(), queue);
  bc::fill(I.dx.begin(), I.dx.end(), 0.0, queue);
  I.dev.launch(I.k_setup, static_cast<size_t>(I.m));  // sg, b, r = b
  I.dev.launch(I.k_apply_t, I.G);                     // s = P A^T r; |s|^2, |b|^2
  I.scalars(P_OP_INIT);
  I.dev.launch(I.k_update_p, I.G);  // p = s
  for (int it = 0; it < iterations; ++it) {
    I.dev.launch(I.k_apply, I.G);  // q = A p; |q|^2
    I.scalars(P_OP_ALPHA);
    I.dev.launch(I.k_update, I.G);   // dx += alpha p; r -= alpha q
    I.dev.launch(I.k_apply_t, I.G);  // s = P A^T r; |s|^2, |r|^2
    I.scalars(P_OP_BETA);
    I.dev.launch(I.k_update_p, I.G);  // p = s + beta p
  }
  if (iterations == 0) I.dev.launch(I.k_apply_t, I.G);  // |r|^2 = |b|^2
  I.scalars(P_OP_RR);
  bc::copy(I.dx.begin(), I.dx.begin() + 3 * static_cast<size_t>(I.n), res.dx.data(), queue);
  double sc[kPolishSlots];
  bc::copy(I.S.begin(), I.S.end(), sc, queue);
  res.iterations = static_cast<int>(sc[P_ITER]);
  res.residual = sc[P_BB] > 0 ? std::sqrt(sc[P_RR] / sc[P_BB]) : 0;
  return res;
}

}  // namespace vpm::detail
