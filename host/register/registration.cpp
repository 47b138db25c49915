#include "vpm/registration.hpp"

#include <Eigen/LU>
#include <Eigen/SVD>
#include <boost/compute/container/vector.hpp>
#include <chrono>
#include <cmath>
#include <sstream>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/locate.hpp"
#include "vpm/volume_map.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"
#include "vpm/untangle.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace bc = boost::compute;

namespace {


std::string fmt3(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

constexpr double kOutsideTolerance = 1e-9;  // |p| > 1 + this: outside the ball
constexpr double kSphereTolerance = 1e-6;   // | |p| - 1 | <= this: on the boundary sphere
constexpr double kDuplicateDistance = 1e-9;

}  // namespace

RegistrationBoundary parse_registration_boundary(const std::string& t) {
  if (t == "tangent") return RegistrationBoundary::Tangent;
  if (t == "samples") return RegistrationBoundary::Samples;
  if (t == "none") return RegistrationBoundary::None;
  throw InputError("--boundary: expected tangent, samples or none, got '" + t + "'");
}
std::string to_string(RegistrationBoundary m) {
  return m == RegistrationBoundary::Tangent ? "tangent" : m == RegistrationBoundary::Samples ? "samples" : "none";
}
RegistrationField parse_registration_field(const std::string& t) {
  if (t == "per-step") return RegistrationField::PerStep;
  if (t == "steady") return RegistrationField::Steady;
  throw InputError("--field: expected per-step or steady, got '" + t + "'");
}
std::string to_string(RegistrationField m) { return m == RegistrationField::PerStep ? "per-step" : "steady"; }

Eigen::Matrix3d kabsch_rotation(const Points& from, const Points& to) {
  const Eigen::Matrix3d h = from.transpose() * to;  // sum p_i q_i^T
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(h, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d u = svd.matrixU(), v = svd.matrixV();
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((v * u.transpose()).determinant() < 0) d(2, 2) = -1;  // refuse the reflection
  return v * d * u.transpose();
}

Eigen::Vector3d pathline(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double t,
                         Eigen::Vector3d* velocity) {
  const Eigen::Vector3d s = (1 - t) * p + t * q, ds = q - p;
  const double np = p.norm(), nq = q.norm();
  const double w = 0.5 * (np + nq);
  Eigen::Vector3d r = s, dr = ds;  // radial part; degenerate cases fall back to the line
  if (np > 1e-12 && nq > 1e-12) {
    const Eigen::Vector3d a = p / np, b = q / nq;
    const double theta = std::acos(std::clamp(a.dot(b), -1.0, 1.0));
    const double rad = (1 - t) * np + t * nq, drad = nq - np;
    if (theta < 1e-7) {
      r = rad * a;
      dr = drad * a;
    } else if (theta < M_PI - 1e-3) {
      const double st = std::sin(theta);
      const Eigen::Vector3d d = (std::sin((1 - t) * theta) * a + std::sin(t * theta) * b) / st;
      const Eigen::Vector3d dd =
          theta * (-std::cos((1 - t) * theta) * a + std::cos(t * theta) * b) / st;
      r = rad * d;
      dr = drad * d + rad * dd;
    }
  }
  if (velocity) *velocity = (1 - w) * ds + w * dr;
  return (1 - w) * s + w * r;
}

std::vector<DivFreeField> registration_fields(const Points& landmarks, const Points& targets,
                                              double lambda, const RegistrationOptions& opt,
                                              Json* fit_report) {
  const int k = opt.steps;
  const Eigen::Index n = landmarks.rows();
  RbfFitOptions fo;
  fo.kernel = opt.boundary == RegistrationBoundary::Tangent ? RbfKernel::Tangent : RbfKernel::Free;
  fo.lambda = lambda;
  if (opt.boundary == RegistrationBoundary::Samples) fo.boundary_samples = fibonacci_sphere(opt.boundary_samples);
  auto samples_at = [&](double t, Points& x, Points& v) {
    for (Eigen::Index i = 0; i < n; ++i) {
      Eigen::Vector3d vel;
      x.row(i) = pathline(landmarks.row(i).transpose(), targets.row(i).transpose(), t, &vel);
      v.row(i) = vel.transpose();
    }
  };
  std::vector<DivFreeField> fields;
  double max_residual = 0, max_condition = 0;
  int regularised = 0, merged = 0, samples = 0;
  if (opt.field == RegistrationField::PerStep) {
    fo.merge_distance = 1e-6;
    for (int s = 0; s <= 2 * k; ++s) {
      Points x(n, 3), v(n, 3);
      samples_at(static_cast<double>(s) / (2 * k), x, v);
      RbfFitInfo info;
      fo.estimate_condition = fit_report && (s == 0 || s == k || s == 2 * k);
      fields.push_back(fit_divfree(x, v, fo, &info));
      max_residual = std::max(max_residual, info.max_residual);
      max_condition = std::max(max_condition, info.condition);
      regularised += info.regularised;
      merged = std::max(merged, info.merged);
      samples = std::max(samples, info.samples);
    }
  } else {
    fo.merge_distance = opt.steady_merge_fraction / std::sqrt(lambda);
    Points x(n * (k + 1), 3), v(n * (k + 1), 3);
    for (int s = 0; s <= k; ++s) {
      Points xs(n, 3), vs(n, 3);
      samples_at(static_cast<double>(s) / k, xs, vs);
      x.middleRows(s * n, n) = xs;
      v.middleRows(s * n, n) = vs;
    }
    RbfFitInfo info;
    fo.estimate_condition = fit_report != nullptr;
    fields.push_back(fit_divfree(x, v, fo, &info));
    max_residual = info.max_residual;
    max_condition = info.condition;
    regularised = info.regularised;
    merged = info.merged;
    samples = info.samples;
  }
  if (fit_report) {
    Json& j = *fit_report;
    j = Json::object();
    j["kernel"] = fo.kernel == RbfKernel::Tangent ? "tangent" : "free";
    j["fields"] = static_cast<int>(fields.size());
    j["samples_per_field"] = samples;
    j["merged_samples"] = merged;
    j["boundary_constraints"] = static_cast<int>(fo.boundary_samples.rows());
    j["max_condition"] = max_condition;
    j["regularised_fits"] = regularised;
    j["max_sample_residual"] = max_residual;
  }
  return fields;
}

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

}  // namespace

void advect(Device& dev, Points& x, const std::vector<DivFreeField>& f, int steps) {
  if (steps < 1) throw InputError("advect: steps must be at least 1");
  if (f.size() != 1 && f.size() != static_cast<size_t>(2 * steps + 1))
    throw InputError("advect: expected 1 or 2K+1 fields");
  if (x.rows() == 0) return;
  if (dev.is_host()) return advect_host(x, f, steps);
  // Pack the distinct fields and the (begin, end) range of each of the 2K+1 slots.
  std::vector<double> centres, coefs;
  std::vector<int> range;
  for (const auto& field : f) {
    const int b = static_cast<int>(centres.size() / 3);
    centres.insert(centres.end(), field.centres.data(), field.centres.data() + field.centres.size());
    coefs.insert(coefs.end(), field.coefficients.data(),
                 field.coefficients.data() + field.coefficients.size());
    range.push_back(b);
    range.push_back(static_cast<int>(centres.size() / 3));
  }
  std::vector<int> slot;
  for (int s = 0; s <= 2 * steps; ++s) {
    const size_t fi = f.size() == 1 ? 0 : static_cast<size_t>(s);
    slot.push_back(range[2 * fi]);
    slot.push_back(range[2 * fi + 1]);
  }
  if (centres.empty()) {
    centres.assign(3, 0.0);
    coefs.assign(3, 0.0);
  }
  // Structure-of-arrays positions, padded to a multiple of the SIMD width (8 lanes of double
  // on CPU devices, 1 elsewhere); padding points sit at the origin and are discarded.
  const int lanes = dev.description().type == "cpu" ? 8 : 1;
  const size_t n = static_cast<size_t>(x.rows());
  const size_t nv = (n + lanes - 1) / lanes, np = nv * lanes;
  std::vector<double> soa(3 * np, 0.0);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) soa[c * np + i] = x(static_cast<Eigen::Index>(i), c);
  auto& q = dev.queue();
  bc::vector<double> dxs(soa.begin(), soa.begin() + np, q);
  bc::vector<double> dys(soa.begin() + np, soa.begin() + 2 * np, q);
  bc::vector<double> dzs(soa.begin() + 2 * np, soa.end(), q);
  bc::vector<int> dslot(slot.begin(), slot.end(), q);
  bc::vector<double> dc(centres.begin(), centres.end(), q);
  bc::vector<double> da(coefs.begin(), coefs.end(), q);
  auto k = dev.kernel("register", "rk4_advect_soa", "-DLANES=" + std::to_string(lanes));
  k.set_arg(0, static_cast<int>(nv));
  k.set_arg(1, dxs);
  k.set_arg(2, dys);
  k.set_arg(3, dzs);
  k.set_arg(4, steps);
  k.set_arg(5, 1.0 / steps);
  k.set_arg(6, dslot);
  k.set_arg(7, dc);
  k.set_arg(8, da);
  k.set_arg(9, f[0].lambda);
  k.set_arg(10, f[0].kernel == RbfKernel::Tangent ? 1 : 0);
  dev.launch(k, nv);
  bc::copy(dxs.begin(), dxs.end(), soa.begin(), q);
  bc::copy(dys.begin(), dys.end(), soa.begin() + np, q);
  bc::copy(dzs.begin(), dzs.end(), soa.begin() + 2 * np, q);
  for (size_t i = 0; i < n; ++i)
    for (int c = 0; c < 3; ++c) x(static_cast<Eigen::Index>(i), c) = soa[c * np + i];
}

Json registration_summary(const RegistrationResult& result, const MapMetrics& against_before) {
  Json r = Json::object();
  r["landmark_rms_error"] = result.landmark_rms_error;
  r["landmark_max_error"] = result.landmark_max_error;
  r["max_normal_velocity"] = result.max_normal_velocity;
  r["inverted_tets"] = against_before.inverted_tets;
  r["vertex_volume_ratio"] = to_json(against_before.vertex_volume_ratio);
  r["tet_volume_ratio"] = to_json(against_before.tet_volume_ratio);
  r["boundary_max_radius_error"] = against_before.boundary_max_radius_error;
  return r;
}

RegistrationResult register_landmarks(Device& dev, Points& ball, const Tets& tets,
                                      const Points& landmarks_in, const Points& targets,
                                      const RegistrationOptions& opt) {
  const auto t_start = Clock::now();
  RegistrationResult res;
  // ---- input checks --------------------------------------------------------------------
  if (landmarks_in.rows() != targets.rows())
    throw InputError("landmarks: " + std::to_string(landmarks_in.rows()) + " landmarks but " +
                     std::to_string(targets.rows()) + " targets");
  if (landmarks_in.rows() == 0) throw InputError("landmarks: no landmarks given");
  if (opt.steps < 1) throw InputError("--steps: must be at least 1");
  if (opt.lambda < 0 || !std::isfinite(opt.lambda)) throw InputError("lambda: must be >= 0");
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < landmarks_in.rows(); ++i) {
    const Eigen::Vector3d p = landmarks_in.row(i).transpose(), q = targets.row(i).transpose();
    const std::string who = "landmark " + std::to_string(i + 1);
    if (!p.allFinite() || !q.allFinite()) throw InputError(who + ": non-finite coordinate");
    if (p.norm() > 1 + kOutsideTolerance)
      throw InputError(who + " " + fmt3(p) + " is outside the unit ball (|p| = " +
                       std::to_string(p.norm()) + ")");
    if (q.norm() > 1 + kOutsideTolerance)
      throw InputError(who + ": target " + fmt3(q) + " is outside the unit ball (|q| = " +
                       std::to_string(q.norm()) + ")");
    const bool pb = std::fabs(p.norm() - 1) <= kSphereTolerance;
    const bool qb = std::fabs(q.norm() - 1) <= kSphereTolerance;
    if (pb != qb)
      throw InputError(who + ": " + (pb ? "the landmark" : "the target") +
                       " lies on the boundary sphere but " + (pb ? "its target" : "the landmark") +
                       " does not; the registration keeps the sphere on itself");
    bool duplicate = false;
    for (Eigen::Index j : keep) {
      if ((landmarks_in.row(j) - landmarks_in.row(i)).norm() > kDuplicateDistance) continue;
      if ((targets.row(j) - targets.row(i)).norm() > kDuplicateDistance)
        throw InputError(who + " " + fmt3(p) + " repeats landmark " + std::to_string(j + 1) +
                         " with a different target");
      duplicate = true;
    }
    if (!duplicate) keep.push_back(i);
  }
  const auto mask = boundary_vertex_mask(static_cast<int>(ball.rows()), boundary_faces(tets));
  {
    for (Eigen::Index v = 0; v < ball.rows(); ++v)
      if (mask[static_cast<size_t>(v)] && std::fabs(ball.row(v).norm() - 1) > kSphereTolerance) {
        std::ostringstream s;
        s << "mesh is not mapped to the unit ball: boundary vertex " << v << " has radius "
          << ball.row(v).norm() << " (run `vpm map` first)";
        throw InputError(s.str());
      }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(keep.size());
  Points p(n, 3), q(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    p.row(i) = landmarks_in.row(keep[static_cast<size_t>(i)]);
    q.row(i) = targets.row(keep[static_cast<size_t>(i)]);
  }
  Json timings = Json::object();
  // ---- rigid step ------------------------------------------------------------------------
  auto t0 = Clock::now();
  if (opt.rigid) res.rotation = kabsch_rotation(p, q);
  const Points before = ball;
  Points x(ball.rows() + landmarks_in.rows(), 3);
  x.topRows(ball.rows()) = ball * res.rotation.transpose();
  x.bottomRows(landmarks_in.rows()) = landmarks_in * res.rotation.transpose();
  p = p * res.rotation.transpose();
  timings["rigid"] = seconds_since(t0);
  // ---- width and fields --------------------------------------------------------------------
  t0 = Clock::now();
  double spacing = std::min(mean_nearest_spacing(p), mean_nearest_spacing(q));
  if (n < 2 || spacing <= 0) spacing = 0.5;
  double factor = opt.width_factor;
  Json loo = Json::array();
  if (opt.lambda > 0) {
    res.lambda = opt.lambda;
  } else {
    if (opt.width_loo && n >= 3) {
      Points v0(n, 3);
      for (Eigen::Index i = 0; i < n; ++i) {
        Eigen::Vector3d vel;
        pathline(p.row(i).transpose(), q.row(i).transpose(), 0.0, &vel);
        v0.row(i) = vel.transpose();
      }
      const RbfKernel kind =
          opt.boundary == RegistrationBoundary::Tangent ? RbfKernel::Tangent : RbfKernel::Free;
      double best = std::numeric_limits<double>::infinity();
      for (double f : {0.5, 0.75, 1.0, 1.5, 2.0, 3.0}) {
        const double w = f * spacing;
        const Eigen::VectorXd e = loo_errors(p, v0, kind, 1 / (w * w));
        const double rms = std::sqrt(e.squaredNorm() / static_cast<double>(n));
        Json entry = Json::object();
        entry["width_factor"] = f;
        entry["loo_rms"] = rms;
        loo.push_back(entry);
        if (rms < best) {
          best = rms;
          factor = f;
        }
      }
    }
    const double width = factor * spacing;
    res.lambda = 1 / (width * width);
  }
  Json fit;
  const std::vector<DivFreeField> fields = registration_fields(p, q, res.lambda, opt, &fit);
  timings["fit"] = seconds_since(t0);
  // ---- advection -------------------------------------------------------------------------
  t0 = Clock::now();
  advect(dev, x, fields, opt.steps);
  timings["advect"] = seconds_since(t0);
  // ---- checks ----------------------------------------------------------------------------
  t0 = Clock::now();
  Points after = x.topRows(ball.rows());
  res.landmarks_final = x.bottomRows(landmarks_in.rows());
  const Eigen::VectorXd err = (res.landmarks_final - targets).rowwise().norm();
  res.landmark_rms_error = std::sqrt(err.squaredNorm() / static_cast<double>(err.size()));
  res.landmark_max_error = err.maxCoeff();
  for (Eigen::Index v = 0; v < after.rows(); ++v) {
    if (!mask[static_cast<size_t>(v)]) continue;
    const double r = after.row(v).norm();
    res.boundary_drift = std::max(res.boundary_drift, std::fabs(r - 1));
    if (opt.project_boundary && r > 0) after.row(v) /= r;
  }
  const Points sphere = fibonacci_sphere(opt.normal_check_samples);
  const size_t nf = fields.size();
  const size_t stride = std::max<size_t>(1, nf / 10);
  std::vector<size_t> check_slots;
  for (size_t s = 0; s < nf; s += stride) check_slots.push_back(s);
  if (check_slots.back() != nf - 1) check_slots.push_back(nf - 1);
  for (size_t s : check_slots) {
    const Points u = evaluate(dev, fields[s], sphere);
    res.max_normal_velocity = std::max(
        res.max_normal_velocity, (u.array() * sphere.array()).rowwise().sum().abs().maxCoeff());
  }
  const Eigen::VectorXd v0 = tet_volumes(dev, before, tets);
  Eigen::VectorXd v1 = tet_volumes(dev, after, tets);
  // Vertices used as landmarks: never moved by untangling or the volume restoration.
  std::vector<char> landmark_vertex(static_cast<size_t>(before.rows()), 0);
  for (Eigen::Index v = 0; v < before.rows(); ++v)
    for (Eigen::Index i = 0; i < landmarks_in.rows(); ++i)
      if ((before.row(v) - landmarks_in.row(i)).squaredNorm() <= 1e-24) landmark_vertex[static_cast<size_t>(v)] = 1;
  Json untangle_report;
  int folded_by_flow = 0;
  if (opt.untangle) {
    std::vector<int> folded;
    for (Eigen::Index t = 0; t < v1.size(); ++t)
      if (v1(t) <= 0 && v0(t) > 0) folded.push_back(static_cast<int>(t));
    folded_by_flow = static_cast<int>(folded.size());
    if (!folded.empty()) {
      const auto t_untangle = Clock::now();
      std::vector<char> fixed(mask.begin(), mask.end());
      for (size_t v = 0; v < fixed.size(); ++v) fixed[v] = fixed[v] || landmark_vertex[v];
      const UntangleResult ur =
          untangle_local(before, tets, after, fixed, folded, opt.untangle_rings, untangle_local_options());
      untangle_report = ur.to_json();
      untangle_report["folded_by_flow"] = folded_by_flow;
      untangle_report["seconds"] = seconds_since(t_untangle);
      v1 = tet_volumes(dev, after, tets);
    }
  }
  int newly_inverted = 0;
  for (Eigen::Index t = 0; t < v1.size(); ++t) {
    if (v1(t) <= 0) ++res.inverted_tets;
    if (v1(t) <= 0 && v0(t) > 0) ++newly_inverted;
  }
  timings["check"] = seconds_since(t0);
  // ---- volume restoration ------------------------------------------------------------------
  Json restore_report;
  if (opt.restore_volumes && res.inverted_tets == 0) {
    t0 = Clock::now();
    VolumeMapOptions vo;
    vo.polish_only = true;
    vo.boundary = MapBoundary::slide;
    vo.pinned = landmark_vertex;
    const TetLocator locator(after, tets);
    for (Eigen::Index i = 0; i < res.landmarks_final.rows(); ++i) {
      const Location l = locator.locate(res.landmarks_final.row(i).transpose());
      if (l.tet >= 0 && l.min_bary >= -1e-9)
        for (int k = 0; k < 4; ++k) vo.pinned[static_cast<size_t>(tets(l.tet, k))] = 1;
    }
    int pinned = 0;
    for (char c : vo.pinned) pinned += c != 0;
    const VolumeMapResult vm = volume_preserving_map(dev, before, tets, after, vo);
    restore_report = Json::object();
    restore_report["vertex_mean_abs_dev_before"] = vm.initial_vertex_mean_abs_dev;
    restore_report["tet_mean_abs_dev_before"] = vm.initial_tet_mean_abs_dev;
    restore_report["vertex_mean_abs_dev"] = vm.final_vertex_mean_abs_dev;
    restore_report["tet_mean_abs_dev"] = vm.final_tet_mean_abs_dev;
    restore_report["rounds"] = static_cast<long>(vm.rounds.size());
    restore_report["pinned_vertices"] = pinned;
    timings["restore"] = seconds_since(t0);
  }
  timings["total"] = seconds_since(t_start);

  Json& r = res.report;
  r = Json::object();
  r["device"] = dev.name();
  r["vertices"] = static_cast<long>(ball.rows());
  r["tets"] = static_cast<long>(tets.rows());
  r["landmarks"] = static_cast<long>(landmarks_in.rows());
  r["steps"] = opt.steps;
  r["lambda"] = res.lambda;
  r["width"] = 1 / std::sqrt(res.lambda);
  r["landmark_spacing"] = spacing;
  if (loo.size() > 0) r["width_loo"] = loo;
  r["boundary"] = to_string(opt.boundary);
  r["field"] = to_string(opt.field);
  const double cosang = std::clamp((res.rotation.trace() - 1) / 2, -1.0, 1.0);
  r["rotation_deg"] = std::acos(cosang) * 180 / M_PI;
  r["landmark_rms_error"] = res.landmark_rms_error;
  r["landmark_max_error"] = res.landmark_max_error;
  r["max_normal_velocity"] = res.max_normal_velocity;
  r["boundary_drift"] = res.boundary_drift;
  r["inverted_tets"] = res.inverted_tets;
  r["folded_by_flow"] = folded_by_flow;
  if (untangle_report.type() != Json::Type::Null) r["untangle"] = untangle_report;
  if (restore_report.type() != Json::Type::Null) r["restore"] = restore_report;
  r["fit"] = fit;
  r["timings_s"] = timings;
  r["newly_inverted_tets"] = newly_inverted;
  if (newly_inverted > 0 && opt.refuse_folds) {
    std::ostringstream s;
    s << "registration folded the mesh: " << newly_inverted << " of " << tets.rows()
      << " tets inverted" << (opt.untangle ? " after local untangling" : "")
      << " (landmark rms error " << res.landmark_rms_error << ", width "
      << 1 / std::sqrt(res.lambda)
      << "): the landmark moves shear the flow more than these tets can follow; use smaller "
         "moves or a finer mesh";
    throw NumericalError(s.str());
  }
  ball = after;
  return res;
}

}  // namespace vpm
