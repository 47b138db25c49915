// The area-preserving map of a closed genus-0 surface to the unit sphere (vpm/surface_map.hpp):
// the sphere map of the initial map's step 2, then Gauss-Newton steps on the face areas whose
// direction is the tet polish's CGLS (map/polish_cgls.hpp) over a backend of triangle rows.
#include "vpm/surface_map.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"
#include "map/polish_cgls.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

using detail::parallel_for;

// The largest log area change one polish step asks of a face.
constexpr double kMaxLogStep = 0.5;
// Trials of a step that flips faces: the flipped faces' vertices are held still and the step
// tried again this many times before it is halved (up to kHalvings times).
constexpr int kFreezeTrials = 8;
constexpr int kHalvings = 12;

Eigen::Vector3d row3(const Points& x, int i) { return x.row(i).transpose(); }

// Twice the signed area vector of face f: (b - a) x (c - a).
Eigen::Vector3d face_normal(const Points& x, const Triangles& f, int t) {
  const Eigen::Vector3d a = row3(x, f(t, 0));
  return (row3(x, f(t, 1)) - a).cross(row3(x, f(t, 2)) - a);
}

Eigen::VectorXd face_areas(const Points& x, const Triangles& f) {
  Eigen::VectorXd a(f.rows());
  parallel_for(static_cast<int>(f.rows()), 16384, [&](int t0, int t1) {
    for (int t = t0; t < t1; ++t) a(t) = 0.5 * face_normal(x, f, t).norm();
  });
  return a;
}

// Chord triangles facing the centre: det(a, b, c) <= 0.
std::vector<int> flipped_list(const Points& x, const Triangles& f) {
  std::vector<int> out;
  for (Eigen::Index t = 0; t < f.rows(); ++t)
    if (row3(x, f(t, 0)).dot(row3(x, f(t, 1)).cross(row3(x, f(t, 2)))) <= 0) out.push_back(static_cast<int>(t));
  return out;
}

// Face area mean |r - 1| of `area` against `area0` (both normalised to their totals).
double face_distortion(const Eigen::VectorXd& area0, const Eigen::VectorXd& area) {
  const double s0 = area0.sum(), s = area.sum();
  double acc = 0;
  for (Eigen::Index t = 0; t < area.size(); ++t) acc += std::abs((area(t) / s) / (area0(t) / s0) - 1.0);
  return acc / static_cast<double>(std::max<Eigen::Index>(1, area.size()));
}

// min |A d - b|^2 over moves d tangent to the sphere at each vertex: A's rows the faces'
// linearised relative area changes, A_(f, v) = grad_v A_f / A_f, b_f = log(t_f / A_f) clamped to
// +-kMaxLogStep (a face 1e-6 too small asks for e^0.5 a step, not for a million-fold growth whose
// linearisation would flip its neighbours; near the target it is 1 - A_f / t_f to first order).
// A^T is applied by gathering over each vertex's faces (no scatter, no races).
class FaceAreaSystem {
 public:
  FaceAreaSystem(const Points& x, const Triangles& faces, const Eigen::VectorXd& target,
                 const std::vector<int>& inc_ptr, const std::vector<int>& inc)
      : x_(x), f_(faces), ptr_(inc_ptr), inc_(inc), n_(static_cast<int>(x.rows())), m_(static_cast<int>(faces.rows())) {
    g_.resize(3 * static_cast<size_t>(m_));
    b_.resize(m_);
    parallel_for(m_, 16384, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) {
        const Eigen::Vector3d a = row3(x_, f_(t, 0)), b = row3(x_, f_(t, 1)), c = row3(x_, f_(t, 2));
        const Eigen::Vector3d nrm = (b - a).cross(c - a);
        const double len = nrm.norm(), area = 0.5 * len;
        const Eigen::Vector3d nh = len > 0 ? Eigen::Vector3d(nrm / len) : Eigen::Vector3d::Zero();
        const double s = 0.5 / area;
        g_[3 * static_cast<size_t>(t)] = s * (b - c).cross(nh);
        g_[3 * static_cast<size_t>(t) + 1] = s * (c - a).cross(nh);
        g_[3 * static_cast<size_t>(t) + 2] = s * (a - b).cross(nh);
        b_(t) = std::clamp(std::log(target(t) / area), -kMaxLogStep, kMaxLogStep);
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
        double u[3] = {acc(0), acc(1), acc(2)};
        detail::pl_tangent(x_(v, 0), x_(v, 1), x_(v, 2), u);
        out.row(v) = Eigen::RowVector3d(u[0], u[1], u[2]);
      }
    });
  }

 private:
  const Points& x_;
  const Triangles& f_;
  const std::vector<int>& ptr_;
  const std::vector<int>& inc_;  // 3 f + k for face f's corner k at the vertex
  const int n_, m_;
  std::vector<Eigen::Vector3d> g_;
  Eigen::VectorXd b_;
};

// polish_cgls's backend over FaceAreaSystem (the tet polish's host backend without holds).
class FaceAreaBackend {
 public:
  explicit FaceAreaBackend(const FaceAreaSystem& sys)
      : sys_(sys), dx_(Points::Zero(sys.vertices(), 3)), s_(sys.vertices(), 3), p_(sys.vertices(), 3), r_(sys.rhs()),
        q_(sys.rows()) {}
  void apply_t() {
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

Points on_sphere(const Points& x) {
  Points y = x;
  for (Eigen::Index i = 0; i < y.rows(); ++i) y.row(i) /= y.row(i).norm();
  return y;
}

}  // namespace

SurfaceMetrics surface_metrics(const Points& reference, const Points& mapped, const Triangles& faces) {
  if (reference.rows() != mapped.rows()) throw InputError("surface_metrics: reference and mapped differ in size");
  SurfaceMetrics m;
  const Eigen::VectorXd a0 = face_areas(reference, faces), a = face_areas(mapped, faces);
  const double s0 = a0.sum(), s = a.sum();
  m.face_ratio.resize(faces.rows());
  for (Eigen::Index t = 0; t < faces.rows(); ++t) m.face_ratio(t) = (a(t) / s) / (a0(t) / s0);
  Eigen::VectorXd d0 = Eigen::VectorXd::Zero(mapped.rows()), d = Eigen::VectorXd::Zero(mapped.rows());
  for (Eigen::Index t = 0; t < faces.rows(); ++t)
    for (int k = 0; k < 3; ++k) {
      d0(faces(t, k)) += a0(t) / 3;
      d(faces(t, k)) += a(t) / 3;
    }
  m.vertex_ratio = (d / s).cwiseQuotient(d0 / s0);
  m.face_area_ratio = ratio_stats(m.face_ratio);
  m.vertex_area_ratio = ratio_stats(m.vertex_ratio);
  m.flipped_faces = static_cast<int>(flipped_list(mapped, faces).size());
  for (Eigen::Index i = 0; i < mapped.rows(); ++i)
    m.max_radius_error = std::max(m.max_radius_error, std::abs(mapped.row(i).norm() - 1.0));
  return m;
}

Json to_json(const SurfaceMetrics& m) {
  Json j = Json::object();
  j["flipped_faces"] = m.flipped_faces;
  j["face_area_ratio"] = to_json(m.face_area_ratio);
  j["vertex_area_ratio"] = to_json(m.vertex_area_ratio);
  j["max_radius_error"] = m.max_radius_error;
  return j;
}

void validate_closed_surface(const TriSurface& s, const std::string& what) {
  const int n = static_cast<int>(s.vertices.rows());
  const Eigen::Index m = s.triangles.rows();
  if (m < 4) throw InputError(what + ": " + std::to_string(m) + " triangles; a closed surface needs at least 4");
  if (!s.vertices.allFinite()) throw InputError(what + ": a vertex coordinate is not finite");
  std::vector<char> used(static_cast<size_t>(n), 0);
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) {
      const int v = s.triangles(t, k);
      if (v < 0 || v >= n)
        throw InputError(what + ": triangle " + std::to_string(t) + ": vertex index " + std::to_string(v) +
                         " out of range (" + std::to_string(n) + " vertices)");
      used[static_cast<size_t>(v)] = 1;
    }
  for (int v = 0; v < n; ++v)
    if (!used[static_cast<size_t>(v)])
      throw InputError(what + ": vertex " + std::to_string(v) + " is in no triangle; the map needs every vertex on the surface");
  const SurfaceTopology st = surface_topology(n, s.triangles);
  if (st.open_edges)
    throw InputError(what + ": edge (" + std::to_string(st.first_bad_edge[0]) + ", " + std::to_string(st.first_bad_edge[1]) +
                     ") is open: the surface has holes (" + std::to_string(st.open_edges) +
                     " open edges); the sphere map needs a closed surface");
  if (st.nonmanifold_edges)
    throw InputError(what + ": edge (" + std::to_string(st.first_bad_edge[0]) + ", " + std::to_string(st.first_bad_edge[1]) +
                     ") has three or more triangles: not a manifold (" + std::to_string(st.nonmanifold_edges) + " such edges)");
  if (st.nonmanifold_vertices)
    throw InputError(what + ": vertex " + std::to_string(st.first_bad_vertex) + ": the surface pinches there (" +
                     std::to_string(st.nonmanifold_vertices) + " non-manifold vertices)");
  if (st.components != 1)
    throw InputError(what + ": " + std::to_string(st.components) + " separate surfaces; the sphere map needs exactly one");
  if (st.euler != 2)
    throw InputError(what + ": Euler characteristic " + std::to_string(st.euler) + " (genus " + std::to_string(st.genus()) +
                     "); the sphere map needs a genus-0 surface (2)");
  // consistent orientation: every directed edge once
  std::vector<std::pair<long long, long long>> directed;
  directed.reserve(3 * static_cast<size_t>(m));
  for (Eigen::Index t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) directed.emplace_back(s.triangles(t, k), s.triangles(t, (k + 1) % 3));
  std::sort(directed.begin(), directed.end());
  for (size_t i = 1; i < directed.size(); ++i)
    if (directed[i] == directed[i - 1])
      throw InputError(what + ": edge (" + std::to_string(directed[i].first) + ", " + std::to_string(directed[i].second) +
                       ") runs the same way in two triangles: the faces are not consistently oriented");
  const Eigen::VectorXd a = face_areas(s.vertices, s.triangles);
  double total = a.sum();
  for (Eigen::Index t = 0; t < m; ++t)
    if (!(a(t) > 1e-14 * total))
      throw InputError(what + ": triangle " + std::to_string(t) + " has no area (" + strprintf("%.3g", a(t)) +
                       "); face area ratios need every face to have one");
}

Json to_json(const SurfaceMapReport& r) {
  Json j = Json::object();
  j["input"]["vertices"] = r.vertices;
  j["input"]["faces"] = r.faces;
  j["input"]["reversed"] = r.reversed;
  j["initial"] = to_json(r.initial);
  j["final"] = to_json(r.final);
  Json& rounds = j["rounds"] = Json::array();
  for (size_t k = 0; k < r.polish.size(); ++k) {
    const SurfaceMapStep& s = r.polish[k];
    Json o = Json::object();
    o["round"] = static_cast<int>(k) + 1;
    o["kind"] = "polish";
    o["face_mean_abs_dev"] = s.face_mean_abs_dev;
    o["solver_iterations"] = s.solver_iterations;
    o["solver_residual"] = s.solver_residual;
    o["step_fraction"] = s.step;
    o["frozen_vertices"] = s.frozen_vertices;
    o["discarded"] = s.discarded;
    o["seconds"] = s.seconds;
    rounds.push_back(o);
  }
  j["sphere_map"] = to_json(r.sphere);
  j["stop_reason"] = r.stop_reason;
  j["converged"] = r.converged;
  j["convergence"]["tolerance"] = r.tolerance;
  j["convergence"]["reached"] = r.final.face_area_ratio.mean_abs_dev;
  j["convergence"]["converged"] = r.converged;
  j["timings_s"]["sphere_map"] = r.seconds_sphere_map;
  j["timings_s"]["polish"] = r.seconds_polish;
  j["timings_s"]["total"] = r.seconds_total;
  return j;
}

SurfaceMapResult map_to_sphere(const TriSurface& input, const SurfaceMapOptions& opt, Device* device) {
  const auto t_total = Clock::now();
  validate_closed_surface(input, "surface");
  SurfaceMapResult res;
  SurfaceMapReport& rep = res.report;
  rep.vertices = static_cast<int>(input.vertices.rows());
  rep.faces = static_cast<int>(input.triangles.rows());
  rep.tolerance = opt.tolerance;
  // the sphere map and the flip test want outward faces: a surface oriented inwards (negative
  // enclosed volume) is mapped with its faces reversed
  TriSurface s = input;
  double volume6 = 0;
  const Eigen::Vector3d c = input.vertices.colwise().mean().transpose();
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    volume6 += (row3(s.vertices, s.triangles(t, 0)) - c)
                   .dot((row3(s.vertices, s.triangles(t, 1)) - c).cross(row3(s.vertices, s.triangles(t, 2)) - c));
  rep.reversed = volume6 < 0;
  if (rep.reversed) s.triangles.col(1).swap(s.triangles.col(2));
  const Triangles& f = s.triangles;

  auto t0 = Clock::now();
  SphereMapResult sm = sphere_map(s, opt.sphere, device);
  rep.sphere = sm.report;
  rep.seconds_sphere_map = seconds_since(t0);
  Points x = on_sphere(sm.sphere);
  rep.initial = surface_metrics(s.vertices, x, f);
  if (rep.initial.flipped_faces > 0)
    throw NumericalError("map_to_sphere: the sphere map left " + std::to_string(rep.initial.flipped_faces) +
                         " flipped faces");
  const Eigen::VectorXd area0 = face_areas(s.vertices, f);
  double d = face_distortion(area0, face_areas(x, f));
  if (opt.progress) opt.progress(strprintf("sphere map: face area mean |r-1| %.4f, %.2f s", d, rep.seconds_sphere_map));

  // vertex -> (face, corner) incidence for the gathers of A^T
  const int n = static_cast<int>(x.rows()), m = static_cast<int>(f.rows());
  std::vector<int> ptr(static_cast<size_t>(n) + 1, 0), inc(3 * static_cast<size_t>(m));
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 3; ++k) ++ptr[static_cast<size_t>(f(t, k)) + 1];
  for (int v = 0; v < n; ++v) ptr[static_cast<size_t>(v) + 1] += ptr[static_cast<size_t>(v)];
  {
    std::vector<int> fill(ptr.begin(), ptr.end() - 1);
    for (int t = 0; t < m; ++t)
      for (int k = 0; k < 3; ++k) inc[static_cast<size_t>(fill[static_cast<size_t>(f(t, k))]++)] = 3 * t + k;
  }

  t0 = Clock::now();
  rep.stop_reason = opt.polish_rounds > 0 ? "rounds" : "none";
  for (int k = 0; k < opt.polish_rounds; ++k) {
    if (d <= opt.tolerance) {
      rep.stop_reason = "tolerance";
      break;
    }
    if (opt.deadline.passed()) {
      rep.stop_reason = "time_budget";
      break;
    }
    const auto t_step = Clock::now();
    const Eigen::VectorXd area = face_areas(x, f);
    const Eigen::VectorXd target = area0 * (area.sum() / area0.sum());
    const FaceAreaSystem sys(x, f, target, ptr, inc);
    FaceAreaBackend bk(sys);
    detail::PolishDirection dir = detail::polish_cgls(bk, opt.polish_iterations);
    SurfaceMapStep st;
    st.solver_iterations = dir.iterations;
    st.solver_residual = dir.residual;
    // the step: where it flips faces their vertices are held still and it is tried again, then
    // halved
    Points y;
    bool ok = false;
    std::vector<char> frozen(static_cast<size_t>(n), 0);
    for (int h = 0; h < kHalvings && !ok; ++h, st.step *= 0.5) {
      for (int trial = 0; trial < kFreezeTrials; ++trial) {
        y = on_sphere(x + st.step * dir.dx);
        const std::vector<int> bad = flipped_list(y, f);
        if (bad.empty()) {
          ok = true;
          break;
        }
        for (int t : bad)
          for (int j = 0; j < 3; ++j) {
            dir.dx.row(f(t, j)).setZero();
            frozen[static_cast<size_t>(f(t, j))] = 1;
          }
      }
      if (ok) break;
    }
    st.frozen_vertices = static_cast<int>(std::count(frozen.begin(), frozen.end(), 1));
    const double dn = ok ? face_distortion(area0, face_areas(y, f)) : d;
    st.discarded = !ok || dn >= d;
    const double before = d;
    if (!st.discarded) {
      x = std::move(y);
      d = dn;
    }
    st.face_mean_abs_dev = d;
    st.seconds = seconds_since(t_step);
    rep.polish.push_back(st);
    if (opt.progress)
      opt.progress(strprintf("polish %d: face area mean |r-1| %.4f, step %g, %.2f s%s", k + 1, d, st.step, st.seconds,
                             st.discarded ? " (discarded)" : ""));
    if (st.discarded || d > (1.0 - opt.polish_min_gain) * before) {
      rep.stop_reason = d <= opt.tolerance ? "tolerance" : "stalled";
      break;
    }
  }
  if (rep.stop_reason == "rounds" && d <= opt.tolerance) rep.stop_reason = "tolerance";
  rep.seconds_polish = seconds_since(t0);
  res.sphere = std::move(x);
  rep.final = surface_metrics(s.vertices, res.sphere, f);
  rep.converged = rep.final.face_area_ratio.mean_abs_dev <= opt.tolerance;
  rep.seconds_total = seconds_since(t_total);
  return res;
}

}  // namespace vpm
