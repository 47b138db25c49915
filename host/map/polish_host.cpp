// The polish direction on the host threads (map/polish.hpp, polish_direction_host): the host
// backend of polish_cgls (map/polish_cgls.hpp), over the linearised per-tet volume equations and
// the soft holds, in the projected space of allowed moves (fixed, tangent, anchored).
#include <Eigen/Dense>
#include <algorithm>

#include "core/parallel.hpp"
#include "map/polish.hpp"
#include "map/polish_cgls.hpp"
#include "mesh/tet_geometry.hpp"

namespace vpm::detail {

// a tet's row of the least squares, shared with kernels/polish.cl (after tet_geometry's; the
// CGLS's scalars and tangent rule, kernels/polish_cgls.clh, come with map/polish_cgls.hpp)
#include "kernels/polish_row.clh"

namespace {

// vertex rows per thread below which the vector updates stay on one
constexpr int kRowBlock = 16384;

// min |A d - b|^2 + |H d|^2 over projected moves d = P d: A's rows are the tets' linearised
// relative volume changes (b = 1 - vol / target), H's the holds' h . sum_k w_k d_(v_k). The
// products with A, H and their transposes.
class HostPolishSystem {
 public:
  HostPolishSystem(const Points& x, const Tets& tets, const Eigen::VectorXd& target, const std::vector<char>& freedom,
                   const std::vector<VolumeAnchor>& anchors, const std::vector<VolumeHold>& holds)
      : x_(x), tets_(tets), freedom_(freedom), holds_(holds), groups_(anchor_groups(anchors)),
        n_(static_cast<int>(x.rows())), m_(static_cast<int>(tets.rows())), nr_(static_cast<int>(holds.size())),
        chunks_(m_ >= 8192 ? 2 : 1), part_(static_cast<size_t>(chunks_)) {
    scaled_gradients(target);
  }

  int vertices() const { return n_; }
  int volume_rows() const { return m_; }
  int hold_rows() const { return nr_; }
  const Eigen::VectorXd& rhs() const { return b_; }

  /// out = A d, out_h = H d (d projected).
  void apply(const Points& d, Eigen::VectorXd& out, Eigen::VectorXd& out_h) const {
    parallel_for(m_, 8192, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) {
        double s = 0;
        s += corner0(t).dot(d.row(tets_(t, 0)).transpose());
        for (int k = 1; k < 4; ++k) s += sg_[3 * static_cast<size_t>(t) + k - 1].dot(d.row(tets_(t, k)).transpose());
        out(t) = s;
      }
    });
    apply_holds(d, out_h);
  }

  /// q = A d and H d, and w = P (A^T q + H^T H d), in one pass over the tets (each row read once,
  /// as apply and apply_t would read it twice); returns |A d|^2 + |H d|^2. Chunks as apply_t's.
  double apply_normal(const Points& d, Points& w) {
    const int per = (m_ + chunks_ - 1) / chunks_;
    std::vector<double> sums(static_cast<size_t>(chunks_), 0.0);
    parallel_for(chunks_, 2, [&](int k0, int k1) {
      for (int j = k0; j < k1; ++j) {
        Points& o = part_[static_cast<size_t>(j)];
        o.setZero(n_, 3);
        double acc = 0;
        const double* dd = d.data();
        double* oo = o.data();
        for (int t = j * per; t < std::min(m_, (j + 1) * per); ++t) {
          const double* g = sg_[3 * static_cast<size_t>(t)].data();  // corners 1..3, 9 doubles
          const double g0[3] = {-g[0] - g[3] - g[6], -g[1] - g[4] - g[7], -g[2] - g[5] - g[8]};  // corner0's order
          const int* T = &tets_(t, 0);
          const double* d0 = dd + 3 * static_cast<size_t>(T[0]);
          double s = g0[0] * d0[0] + g0[1] * d0[1] + g0[2] * d0[2];
          for (int k = 1; k < 4; ++k) {
            const double* dk = dd + 3 * static_cast<size_t>(T[k]);
            const double* gk = g + 3 * (k - 1);
            s += gk[0] * dk[0] + gk[1] * dk[1] + gk[2] * dk[2];
          }
          acc += s * s;
          double* o0 = oo + 3 * static_cast<size_t>(T[0]);
          for (int c = 0; c < 3; ++c) o0[c] += s * g0[c];
          for (int k = 1; k < 4; ++k) {
            double* ok = oo + 3 * static_cast<size_t>(T[k]);
            const double* gk = g + 3 * (k - 1);
            for (int c = 0; c < 3; ++c) ok[c] += s * gk[c];
          }
        }
        sums[static_cast<size_t>(j)] = acc;
      }
    });
    double qq = sums[0];
    for (int j = 1; j < chunks_; ++j) qq += sums[static_cast<size_t>(j)];
    Eigen::VectorXd q_h(nr_);
    apply_holds(d, q_h);
    sum_parts(q_h, w);
    return qq + q_h.squaredNorm();
  }

  /// out = P (A^T y + H^T y_h): tets split into fixed chunks, each scattering into its own
  /// buffer (no races, and the result does not depend on the number of threads), then summed.
  void apply_t(const Eigen::VectorXd& y, const Eigen::VectorXd& y_h, Points& out) {
    const int per = (m_ + chunks_ - 1) / chunks_;
    parallel_for(chunks_, 2, [&](int k0, int k1) {
      for (int j = k0; j < k1; ++j) {
        Points& o = part_[static_cast<size_t>(j)];
        o.setZero(n_, 3);
        for (int t = j * per; t < std::min(m_, (j + 1) * per); ++t)
          for (int k = 0; k < 4; ++k)
            o.row(tets_(t, k)) += y(t) * (k ? sg_[3 * static_cast<size_t>(t) + k - 1] : corner0(t)).transpose();
      }
    });
    sum_parts(y_h, out);
  }

 private:
  // out_h = H d: each hold's direction . sum_k w_k d_(v_k)
  void apply_holds(const Points& d, Eigen::VectorXd& out_h) const {
    for (int r = 0; r < nr_; ++r) {
      const VolumeHold& h = holds_[static_cast<size_t>(r)];
      Eigen::Vector3d acc = Eigen::Vector3d::Zero();
      for (int k = 0; k < 4; ++k)
        acc += h.weights[static_cast<size_t>(k)] * d.row(h.vertices[static_cast<size_t>(k)]).transpose();
      out_h(r) = h.direction.dot(acc);
    }
  }

  // out = P (the chunks' scattered A^T y summed + H^T y_h), the sum per vertex on the threads
  void sum_parts(const Eigen::VectorXd& y_h, Points& out) const {
    out.resize(n_, 3);
    parallel_for(n_, kRowBlock, [&](int v0, int v1) {
      out.middleRows(v0, v1 - v0) = part_[0].middleRows(v0, v1 - v0);
      for (int j = 1; j < chunks_; ++j) out.middleRows(v0, v1 - v0) += part_[static_cast<size_t>(j)].middleRows(v0, v1 - v0);
    });
    for (int r = 0; r < nr_; ++r) {
      const VolumeHold& h = holds_[static_cast<size_t>(r)];
      for (int k = 0; k < 4; ++k)
        out.row(h.vertices[static_cast<size_t>(k)]) +=
            (y_h(r) * h.weights[static_cast<size_t>(k)]) * h.direction.transpose();
    }
    project(out);
  }

  // Per-tet scaled gradients sg_{t,k} = vol_t grad phi_k / target_t, kept for k = 1..3 only
  // (sg_[3 t + k - 1]); corner 0's, minus their sum, is recomputed where it is used, in the
  // same order of operations (the loops are memory-bound: a quarter less to read).
  void scaled_gradients(const Eigen::VectorXd& target) {
    sg_.resize(3 * static_cast<size_t>(m_));
    b_.resize(m_);
    parallel_for(m_, 8192, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) {
        double e[3][3], g[12];
        tet_edges(x_, tets_, t, e);
        b_(t) = pl_row(e[0], e[1], e[2], target(t), g);
        for (int q = 0; q < 3; ++q) sg_[3 * static_cast<size_t>(t) + q] = Eigen::Vector3d(g[3 + 3 * q], g[4 + 3 * q], g[5 + 3 * q]);
      }
    });
  }

  Eigen::Vector3d corner0(int t) const {
    Eigen::Vector3d g0 = Eigen::Vector3d::Zero();
    for (int q = 0; q < 3; ++q) g0 -= sg_[3 * static_cast<size_t>(t) + q];
    return g0;
  }

  // d <- P d: fixed vertices zeroed, tangent ones projected on the sphere's tangent plane, each
  // anchor group's moves projected on the null space of its constraints.
  void project(Points& d) const {
    parallel_for(n_, kRowBlock, [&](int v0, int v1) {
      for (int v = v0; v < v1; ++v) {
        if (freedom_[v] == kPolishFixed) {
          d.row(v).setZero();
        } else if (freedom_[v] == kPolishTangent) {
          double u[3] = {d(v, 0), d(v, 1), d(v, 2)};
          pl_tangent(x_(v, 0), x_(v, 1), x_(v, 2), u);
          d.row(v) = Eigen::RowVector3d(u[0], u[1], u[2]);
        }
      }
    });
    for (int gi = 0; gi < groups_.groups(); ++gi) {
      const int b = groups_.ptr[static_cast<size_t>(gi)], k = groups_.ptr[static_cast<size_t>(gi) + 1] - b;
      const double* P = groups_.matrix.data() + groups_.offset[static_cast<size_t>(gi)];
      Points dv(k, 3);
      for (int i = 0; i < k; ++i) dv.row(i) = d.row(groups_.vertices[static_cast<size_t>(b + i)]);
      for (int i = 0; i < k; ++i) {
        Eigen::RowVector3d o = Eigen::RowVector3d::Zero();
        for (int j = 0; j < k; ++j) o += P[i * k + j] * dv.row(j);
        d.row(groups_.vertices[static_cast<size_t>(b + i)]) = o;
      }
    }
  }

  const Points& x_;
  const Tets& tets_;
  const std::vector<char>& freedom_;
  const std::vector<VolumeHold>& holds_;
  const AnchorGroups groups_;
  const int n_, m_, nr_, chunks_;
  std::vector<Points> part_;
  std::vector<Eigen::Vector3d> sg_;
  Eigen::VectorXd b_;
};

// polish_cgls's host backend: the iteration's vectors and scalars on the host, the products
// HostPolishSystem's (q and w in one pass, apply_normal); the sums are Eigen's squared norms.
class HostPolishBackend {
 public:
  explicit HostPolishBackend(HostPolishSystem& sys)
      : sys_(sys), dx_(Points::Zero(sys.vertices(), 3)), s_(sys.vertices(), 3), p_(sys.vertices(), 3),
        w_(sys.vertices(), 3) {}

  void start() {
    sys_.apply_t(sys_.rhs(), Eigen::VectorXd::Zero(sys_.hold_rows()), s_);
    sum_ = s_.squaredNorm();
  }
  void apply() { sum_ = sys_.apply_normal(p_, w_); }
  void scalars(int op) { pl_scalars(op, sum_, op == P_OP_INIT ? sys_.rhs().squaredNorm() : 0.0, S_); }
  void update() {
    const double alpha = S_[P_ALPHA];
    sum_ = halves([&](int v0, int v1) {
      const auto rows = [&](Points& m) { return m.middleRows(v0, v1 - v0); };
      rows(dx_) += alpha * rows(p_);
      rows(s_) -= alpha * rows(w_);
      return rows(s_).squaredNorm();
    });
  }
  void update_p() {
    const double beta = S_[P_BETA];
    halves([&](int v0, int v1) {
      if (beta == 0) p_.middleRows(v0, v1 - v0) = s_.middleRows(v0, v1 - v0);
      else p_.middleRows(v0, v1 - v0) = s_.middleRows(v0, v1 - v0) + beta * p_.middleRows(v0, v1 - v0);
      return 0.0;
    });
  }
  bool stopped() const { return S_[P_STOP] != 0; }
  PolishDirection result() {
    PolishDirection res;
    const double bn = sys_.rhs().norm();
    if (bn > 0) {
      Eigen::VectorXd q(sys_.volume_rows()), q_h(sys_.hold_rows());
      sys_.apply(dx_, q, q_h);
      res.residual = (sys_.rhs() - q).norm() / bn;
    }
    res.dx = std::move(dx_);
    res.iterations = static_cast<int>(S_[P_ITER]);
    return res;
  }

 private:
  // body(v0, v1) over the vertices in two fixed halves (on two threads from kRowBlock rows), its
  // results summed: the sums do not depend on the number of threads
  template <class Body>
  double halves(Body body) {
    const int n = sys_.vertices();
    if (n < 2 * kRowBlock) return body(0, n);
    double part[2] = {0, 0};
    parallel_for(2, 2, [&](int k0, int k1) {
      for (int k = k0; k < k1; ++k) part[k] = body(k * (n / 2), k ? n : n / 2);
    });
    return part[0] + part[1];
  }

  HostPolishSystem& sys_;
  Points dx_, s_, p_, w_;
  double sum_ = 0;
  double S_[P_SLOTS] = {};
};

}  // namespace

PolishDirection polish_direction_host(const Points& x, const Tets& tets, const Eigen::VectorXd& target,
                                      const std::vector<char>& freedom, const std::vector<VolumeAnchor>& anchors,
                                      int iterations, const std::vector<VolumeHold>& holds) {
  HostPolishSystem sys(x, tets, target, freedom, anchors, holds);
  HostPolishBackend bk(sys);
  return polish_cgls(bk, iterations);
}

}  // namespace vpm::detail
