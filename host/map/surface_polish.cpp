// The polish of a surface map's face areas (map/surface_polish.hpp): Gauss-Newton steps whose
// direction is the tet polish's CGLS (map/polish_cgls.hpp) over a backend of triangle rows, the
// moves those the domain allows.
#include "map/surface_polish.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"
#include "map/polish_cgls.hpp"
#include "map/surface_area.hpp"
#include "vpm/format.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

Eigen::Vector3d SurfaceDomainMoves::project(const Points& x, int v, const Eigen::Vector3d& u) const {
  if (!fixed.empty() && fixed[static_cast<size_t>(v)]) return Eigen::Vector3d::Zero();
  if (domain == SurfaceDomain::sphere) {
    double w[3] = {u(0), u(1), u(2)};
    pl_tangent(x(v, 0), x(v, 1), x(v, 2), w);
    return {w[0], w[1], w[2]};
  }
  if (!boundary[static_cast<size_t>(v)]) return {u(0), u(1), 0.0};
  const Eigen::Vector3d t(-x(v, 1), x(v, 0), 0.0);  // along the circle
  const double len2 = t.squaredNorm();
  return len2 > 0 ? Eigen::Vector3d(t * (t.dot(u) / len2)) : Eigen::Vector3d::Zero();
}

Points SurfaceDomainMoves::place(const Points& x) const {
  Points y = x;
  if (domain == SurfaceDomain::sphere) {
    for (Eigen::Index i = 0; i < y.rows(); ++i) y.row(i) /= y.row(i).norm();
    return y;
  }
  y.col(2).setZero();
  for (Eigen::Index i = 0; i < y.rows(); ++i)
    if (boundary[static_cast<size_t>(i)]) y.row(i) /= y.row(i).norm();
  return y;
}

std::vector<int> SurfaceDomainMoves::flipped(const Points& x, const Triangles& f) const {
  return flipped_faces_in(domain, x, f);
}

namespace {

// The largest log area change one polish step asks of a face.
constexpr double kMaxLogStep = 0.5;
// Trials of a step that flips faces: the flipped faces' vertices are held still, the direction
// solved again and the step tried again this many times before it is halved (up to kHalvings).
constexpr int kFreezeTrials = 8;
constexpr int kHalvings = 12;
// The polish stops once the last kGainWindow steps together gained less than kGainWindow x
// SurfaceMapOptions::polish_min_gain: one step's gain varies from step to step (faces held
// still in one step move in the next), and a rule on one step stopped early by chance.
constexpr size_t kGainWindow = 5;

Eigen::Vector3d point_of(const Points& x, int i) { return x.row(i).transpose(); }

// Face area mean |r - 1| of `area` against `area0` (both normalised to their totals).
double face_distortion(const Eigen::VectorXd& area0, const Eigen::VectorXd& area) {
  const double s0 = area0.sum(), s = area.sum();
  double acc = 0;
  for (Eigen::Index t = 0; t < area.size(); ++t) acc += std::abs((area(t) / s) / (area0(t) / s0) - 1.0);
  return acc / static_cast<double>(std::max<Eigen::Index>(1, area.size()));
}

// min |W (A d - b)|^2 over the moves d the domain allows (tangent to the sphere; in the disk's
// plane, along the circle on its boundary): A's rows the faces'
// linearised relative area changes, A_(f, v) = grad_v A_f / A_f, b_f = log(t_f / A_f) clamped to
// +-kMaxLogStep (a face 1e-6 too small asks for e^0.5 a step, not for a million-fold growth whose
// linearisation would flip its neighbours; near the target it is 1 - A_f / t_f to first order).
// W_f = sqrt(min(1, A_f / t_f)): a crushed face's row, whose gradient grows like 1 / its size,
// would otherwise take the early-stopped CGLS's iterations from the bulk of the faces (chosen on
// the development surfaces of docs/surfaces.md: the AAL surface 1.04 % -> 0.49 %).
// A^T is applied by gathering over each vertex's faces (no scatter, no races).
class FaceAreaSystem {
 public:
  FaceAreaSystem(const SurfaceDomainMoves& domain, const Points& x, const Triangles& faces, const Eigen::VectorXd& target,
                 const std::vector<int>& inc_ptr, const std::vector<int>& inc)
      : domain_(domain), x_(x), f_(faces), ptr_(inc_ptr), inc_(inc), n_(static_cast<int>(x.rows())),
        m_(static_cast<int>(faces.rows())) {
    g_.resize(3 * static_cast<size_t>(m_));
    b_.resize(m_);
    parallel_for(m_, 16384, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) {
        const Eigen::Vector3d a = point_of(x_, f_(t, 0)), b = point_of(x_, f_(t, 1)), c = point_of(x_, f_(t, 2));
        const Eigen::Vector3d nrm = (b - a).cross(c - a);
        const double len = nrm.norm(), area = std::max(0.5 * len, 1e-300);
        const Eigen::Vector3d nh = len > 0 ? Eigen::Vector3d(nrm / len) : Eigen::Vector3d::Zero();
        const double w = std::sqrt(std::min(1.0, area / target(t)));
        const double s = 0.5 / area * w;
        g_[3 * static_cast<size_t>(t)] = s * (b - c).cross(nh);
        g_[3 * static_cast<size_t>(t) + 1] = s * (c - a).cross(nh);
        g_[3 * static_cast<size_t>(t) + 2] = s * (a - b).cross(nh);
        b_(t) = w * std::clamp(std::log(target(t) / area), -kMaxLogStep, kMaxLogStep);
      }
    });
  }
  int vertices() const { return n_; }
  int rows() const { return m_; }
  const Eigen::VectorXd& rhs() const { return b_; }

  void apply(const Points& d, Eigen::VectorXd& out) const {
    parallel_for(m_, 16384, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) {
        double s = 0;
        for (int k = 0; k < 3; ++k) s += g_[3 * static_cast<size_t>(t) + k].dot(d.row(f_(t, k)).transpose());
        out(t) = s;
      }
    });
  }
  void apply_t(const Eigen::VectorXd& y, Points& out) const {
    parallel_for(n_, 8192, [&](int v0, int v1) {
      for (int v = v0; v < v1; ++v) {
        Eigen::Vector3d acc = Eigen::Vector3d::Zero();
        for (int j = ptr_[static_cast<size_t>(v)]; j < ptr_[static_cast<size_t>(v) + 1]; ++j)
          acc += y(inc_[static_cast<size_t>(j)] / 3) * g_[static_cast<size_t>(inc_[static_cast<size_t>(j)])];
        out.row(v) = domain_.project(x_, v, acc).transpose();
      }
    });
  }

 private:
  const SurfaceDomainMoves& domain_;
  const Points& x_;
  const Triangles& f_;
  const std::vector<int>& ptr_;
  const std::vector<int>& inc_;  // 3 f + k for face f's corner k at the vertex
  const int n_, m_;
  std::vector<Eigen::Vector3d> g_;
  Eigen::VectorXd b_;
};

// polish_cgls's backend over FaceAreaSystem (the tet polish's host backend without holds). It
// keeps the residual r = b - A dx and forms s = A^T r from it in update() (CGLS's residual form,
// where the tet backends carry s by its recurrence): A^T is a gather here, so the recurrence would
// save no pass, and the surface maps keep the directions they were tuned with (the folded AAL
// surface of docs/surfaces.md stalls at 0.65 % under the recurrence, 0.49 % without).
class FaceAreaBackend {
 public:
  explicit FaceAreaBackend(const FaceAreaSystem& sys)
      : sys_(sys), dx_(Points::Zero(sys.vertices(), 3)), s_(sys.vertices(), 3), p_(sys.vertices(), 3), r_(sys.rhs()),
        q_(sys.rows()) {}
  void start() {
    sys_.apply_t(r_, s_);
    sum_ = s_.squaredNorm();
  }
  void apply() {
    sys_.apply(p_, q_);
    sum_ = q_.squaredNorm();
  }
  void scalars(int op) { detail::pl_scalars(op, sum_, op == P_OP_INIT ? sys_.rhs().squaredNorm() : 0.0, S_); }
  void update() {
    dx_ += S_[P_ALPHA] * p_;
    r_ -= S_[P_ALPHA] * q_;
    sys_.apply_t(r_, s_);
    sum_ = s_.squaredNorm();
  }
  void update_p() {
    if (S_[P_BETA] == 0) p_ = s_;
    else p_ = s_ + S_[P_BETA] * p_;
  }
  bool stopped() const { return S_[P_STOP] != 0; }
  detail::PolishDirection result() {
    detail::PolishDirection res;
    res.dx = std::move(dx_);
    res.iterations = static_cast<int>(S_[P_ITER]);
    const double bn = sys_.rhs().norm();
    res.residual = bn > 0 ? r_.norm() / bn : 0;
    return res;
  }

 private:
  const FaceAreaSystem& sys_;
  Points dx_, s_, p_;
  Eigen::VectorXd r_, q_;
  double sum_ = 0;
  double S_[P_SLOTS] = {};
};

// Each vertex's (face, corner) pairs as 3 f + k, CSR: the gathers of A^T.
struct FaceIncidence {
  std::vector<int> ptr, items;
};
FaceIncidence vertex_face_incidence(int n, const Triangles& f) {
  FaceIncidence inc;
  inc.ptr.assign(static_cast<size_t>(n) + 1, 0);
  inc.items.resize(3 * static_cast<size_t>(f.rows()));
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k) ++inc.ptr[static_cast<size_t>(f(t, k)) + 1];
  for (int v = 0; v < n; ++v) inc.ptr[static_cast<size_t>(v) + 1] += inc.ptr[static_cast<size_t>(v)];
  std::vector<int> fill(inc.ptr.begin(), inc.ptr.end() - 1);
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    for (int k = 0; k < 3; ++k)
      inc.items[static_cast<size_t>(fill[static_cast<size_t>(f(t, k))]++)] = 3 * static_cast<int>(t) + k;
  return inc;
}

// One polish step from x (kept when it lowers the face distortion d, which is then updated):
// the CGLS direction; where it flips faces, solved again with their vertices held still and tried
// again; halved while it flips or does not lower d. Zeroing the held vertices' moves in the first
// direction instead (which counted on them) stalled limbed surfaces: the cow of docs/surfaces.md
// at 7.1 % instead of 3.1 %.
SurfaceMapStep polish_step(const SurfaceDomainMoves& domain, const Triangles& f, const Eigen::VectorXd& area0, const FaceIncidence& inc, int iterations,
                           Points& x, double& d) {
  const auto t_step = Clock::now();
  const Eigen::VectorXd area = face_areas(x, f);
  const Eigen::VectorXd target = area0 * (area.sum() / area0.sum());
  const FaceAreaSystem sys(domain, x, f, target, inc.ptr, inc.items);
  FaceAreaBackend bk(sys);
  detail::PolishDirection dir = detail::polish_cgls(bk, iterations);
  SurfaceMapStep st;
  st.solver_iterations = dir.iterations;
  st.solver_residual = dir.residual;
  SurfaceDomainMoves held = domain;
  if (held.fixed.empty()) held.fixed.assign(static_cast<size_t>(x.rows()), 0);
  const auto count_held = [](const std::vector<char>& v) { return std::count(v.begin(), v.end(), 1); };
  const auto held_before = count_held(held.fixed);
  st.discarded = true;
  for (int h = 0; h < kHalvings && st.discarded; ++h, st.step *= 0.5) {
    bool ok = false;
    Points y;
    for (int trial = 0; trial < kFreezeTrials && !ok; ++trial) {
      y = domain.place(x + st.step * dir.dx);
      const std::vector<int> bad = domain.flipped(y, f);
      ok = bad.empty();
      for (int t : bad)
        for (int j = 0; j < 3; ++j) held.fixed[static_cast<size_t>(f(t, j))] = 1;
      if (!ok) {  // the direction solved again with those vertices held
        const FaceAreaSystem again(held, x, f, target, inc.ptr, inc.items);
        FaceAreaBackend again_bk(again);
        dir.dx = detail::polish_cgls(again_bk, iterations).dx;
      }
    }
    if (!ok) continue;
    const double dn = face_distortion(area0, face_areas(y, f));
    if (dn < d) {
      x = std::move(y);
      d = dn;
      st.discarded = false;
      break;
    }
  }
  st.frozen_vertices = static_cast<int>(count_held(held.fixed) - held_before);
  st.face_mean_abs_dev = d;
  st.seconds = seconds_since(t_step);
  return st;
}

}  // namespace

// long: the steps and their stopping rule, one place
void polish_surface(const SurfaceDomainMoves& domain, const Triangles& f, const Eigen::VectorXd& area0,
                    const SurfaceMapOptions& opt, Points& x, SurfaceMapReport& rep) {
  double d = face_distortion(area0, face_areas(x, f));
  auto t0 = Clock::now();
  const FaceIncidence inc = vertex_face_incidence(static_cast<int>(x.rows()), f);
  rep.stop_reason = opt.polish_rounds > 0 ? "rounds" : "none";
  std::vector<double> history;  // the distortion before each step
  for (int k = 0; k < opt.polish_rounds; ++k) {
    if (d <= opt.tolerance || opt.deadline.passed()) {
      rep.stop_reason = d <= opt.tolerance ? "tolerance" : "time_budget";
      break;
    }
    history.push_back(d);
    const SurfaceMapStep st = polish_step(domain, f, area0, inc, opt.polish_iterations, x, d);
    rep.polish.push_back(st);
    if (opt.progress)
      opt.progress(strprintf("polish %d: face area mean |r-1| %.4f, step %g, %.2f s%s", k + 1, d, st.step, st.seconds,
                             st.discarded ? " (discarded)" : ""));
    const size_t h = history.size();
    if (st.discarded || (h >= kGainWindow && d > (1.0 - kGainWindow * opt.polish_min_gain) * history[h - kGainWindow])) {
      rep.stop_reason = d <= opt.tolerance ? "tolerance" : "stalled";
      break;
    }
  }
  if (rep.stop_reason == "rounds" && d <= opt.tolerance) rep.stop_reason = "tolerance";
  rep.seconds_polish = seconds_since(t0);
}

}  // namespace vpm::detail
