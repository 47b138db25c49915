// ---- width and fields: pathlines and the divergence-free fits along them ----
#include <algorithm>
#include <cmath>
#include <limits>

#include "register/registration_steps.hpp"

namespace vpm {

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

namespace {

RbfKernel registration_kernel(const RegistrationOptions& opt) {
  return opt.boundary == RegistrationBoundary::Tangent ? RbfKernel::Tangent : RbfKernel::Free;
}

/// Pathline points `x` and velocities `v` (N x 3) of all landmarks at time t.
void pathline_samples(const Points& landmarks, const Points& targets, double t, Points& x, Points& v) {
  for (Eigen::Index i = 0; i < landmarks.rows(); ++i) {
    Eigen::Vector3d vel;
    x.row(i) = pathline(landmarks.row(i).transpose(), targets.row(i).transpose(), t, &vel);
    v.row(i) = vel.transpose();
  }
}

/// One field per RK4 stage time s / 2K; conditions estimated at the first, middle and last.
std::vector<DivFreeField> fit_per_step(const Points& landmarks, const Points& targets, int k, RbfFitOptions fo,
                                       RegistrationFitReport& rep, bool estimate) {
  std::vector<DivFreeField> fields;
  fo.merge_distance = 1e-6;
  const Eigen::Index n = landmarks.rows();
  for (int s = 0; s <= 2 * k; ++s) {
    Points x(n, 3), v(n, 3);
    pathline_samples(landmarks, targets, static_cast<double>(s) / (2 * k), x, v);
    RbfFitInfo info;
    fo.estimate_condition = estimate && (s == 0 || s == k || s == 2 * k);
    fields.push_back(fit_divfree(x, v, fo, &info));
    rep.max_sample_residual = std::max(rep.max_sample_residual, info.max_residual);
    rep.max_condition = std::max(rep.max_condition, info.condition);
    rep.regularised_fits += info.regularised;
    rep.merged_samples = std::max(rep.merged_samples, info.merged);
    rep.samples_per_field = std::max(rep.samples_per_field, info.samples);
  }
  return fields;
}

/// One time-independent field through the pathline samples of all K + 1 step times.
DivFreeField fit_steady(const Points& landmarks, const Points& targets, int k, RbfFitOptions fo,
                        double merge_distance, RegistrationFitReport& rep, bool estimate) {
  const Eigen::Index n = landmarks.rows();
  fo.merge_distance = merge_distance;
  Points x(n * (k + 1), 3), v(n * (k + 1), 3);
  for (int s = 0; s <= k; ++s) {
    Points xs(n, 3), vs(n, 3);
    pathline_samples(landmarks, targets, static_cast<double>(s) / k, xs, vs);
    x.middleRows(s * n, n) = xs;
    v.middleRows(s * n, n) = vs;
  }
  RbfFitInfo info;
  fo.estimate_condition = estimate;
  DivFreeField field = fit_divfree(x, v, fo, &info);
  rep.max_sample_residual = info.max_residual;
  rep.max_condition = info.condition;
  rep.regularised_fits = info.regularised;
  rep.merged_samples = info.merged;
  rep.samples_per_field = info.samples;
  return field;
}

}  // namespace

std::vector<DivFreeField> registration_fields(const Points& landmarks, const Points& targets,
                                              double lambda, const RegistrationOptions& opt,
                                              RegistrationFitReport* fit_report) {
  RbfFitOptions fo;
  fo.kernel = registration_kernel(opt);
  fo.lambda = lambda;
  if (opt.boundary == RegistrationBoundary::Samples) fo.boundary_samples = fibonacci_sphere(opt.boundary_samples);
  RegistrationFitReport rep;
  std::vector<DivFreeField> fields;
  if (opt.field == RegistrationField::PerStep)
    fields = fit_per_step(landmarks, targets, opt.steps, fo, rep, fit_report != nullptr);
  else
    fields.push_back(fit_steady(landmarks, targets, opt.steps, fo, opt.steady_merge_fraction / std::sqrt(lambda),
                                rep, fit_report != nullptr));
  if (fit_report) {
    rep.kernel = fo.kernel;
    rep.fields = static_cast<int>(fields.size());
    rep.boundary_constraints = static_cast<int>(fo.boundary_samples.rows());
    *fit_report = rep;
  }
  return fields;
}

Json to_json(const RegistrationFitReport& fit) {
  Json j = Json::object();
  j["kernel"] = fit.kernel == RbfKernel::Tangent ? "tangent" : "free";
  j["fields"] = fit.fields;
  j["samples_per_field"] = fit.samples_per_field;
  j["merged_samples"] = fit.merged_samples;
  j["boundary_constraints"] = fit.boundary_constraints;
  j["max_condition"] = fit.max_condition;
  j["regularised_fits"] = fit.regularised_fits;
  j["max_sample_residual"] = fit.max_sample_residual;
  return j;
}

namespace {

/// The width factor in {0.5, ..., 3} whose interpolant of the initial landmark velocities has
/// the smallest RMS leave-one-out error (`factor` keeps its value on ties with infinity).
double loo_width_factor(const Points& p, const Points& q, double spacing, const RegistrationOptions& opt,
                        double factor, std::vector<WidthLooCandidate>& candidates) {
  const Eigen::Index n = p.rows();
  Points v0(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::Vector3d vel;
    pathline(p.row(i).transpose(), q.row(i).transpose(), 0.0, &vel);
    v0.row(i) = vel.transpose();
  }
  double best = std::numeric_limits<double>::infinity();
  for (double f : {0.5, 0.75, 1.0, 1.5, 2.0, 3.0}) {
    const double w = f * spacing;
    const Eigen::VectorXd e = loo_errors(p, v0, registration_kernel(opt), 1 / (w * w));
    const double rms = std::sqrt(e.squaredNorm() / static_cast<double>(n));
    candidates.push_back({f, rms});
    if (rms < best) {
      best = rms;
      factor = f;
    }
  }
  return factor;
}

}  // namespace

RegistrationWidth choose_width(const Points& p, const Points& q, const RegistrationOptions& opt) {
  RegistrationWidth w;
  const Eigen::Index n = p.rows();
  w.spacing = std::min(mean_nearest_spacing(p), mean_nearest_spacing(q));
  if (n < 2 || w.spacing <= 0) w.spacing = 0.5;
  if (opt.lambda > 0) {
    w.lambda = opt.lambda;
    return w;
  }
  double factor = opt.width_factor;
  if (opt.width_loo && n >= 3) factor = loo_width_factor(p, q, w.spacing, opt, factor, w.loo);
  const double width = factor * w.spacing;
  w.lambda = 1 / (width * width);
  return w;
}

}  // namespace vpm
