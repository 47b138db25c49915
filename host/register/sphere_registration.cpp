// Area-preserving landmark registration on the unit sphere (vpm/surface_registration.hpp): the
// great-circle pathlines, the surface-divergence-free Gaussian field fitted to them at each RK4
// stage time, the advection of every vertex and the last step onto the targets.
#include "vpm/surface_registration.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "core/parallel.hpp"
#include "map/surface_area.hpp"
#include "map/surface_polish.hpp"
#include "register/dense_surface.hpp"
#include "register/landmark_gram.hpp"
#include "register/sphere_field.hpp"
#include "register/sphere_match.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/registration.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace {

using Eigen::Vector3d;
using detail::exp_map;
using detail::log_map;
using detail::SphereField;
using detail::tangent_basis;
using detail::weight_basis;
using detail::gaussian_hessian;

// The width factors leave-one-out chooses among (SurfaceRegistrationOptions::width_factor 0).
constexpr double kWidthFactors[] = {0.5, 1, 1.5, 2, 3, 4};

// The Gaussian's width in chord length for `factor` x the landmarks' mean angular `spacing`.
double chord_width(double factor, double spacing) { return 2 * std::sin(std::min(factor * spacing, M_PI) / 2); }

// The field whose values at `at` (unit vectors) are the tangent vectors `velocity`: with
// P_i = [x_i]×^T B_i the Gram matrix G_ij = P_i^T H_ij P_j is symmetric positive definite, and
// u_j = P_j a_j.
struct Gram {
  std::vector<Eigen::Matrix<double, 3, 2>> P, B;
  Eigen::MatrixXd G;
  Eigen::VectorXd rhs;
};

Gram gram(const std::vector<Vector3d>& at, const std::vector<Vector3d>& velocity, double lambda) {
  const int L = static_cast<int>(at.size());
  Gram g;
  std::vector<Eigen::Matrix<double, 3, 2>>& P = g.P;
  std::vector<Eigen::Matrix<double, 3, 2>>& B = g.B;
  P.resize(L);
  B.resize(L);
  for (int i = 0; i < L; ++i) {
    B[i] = tangent_basis(at[i]);
    P[i] = weight_basis(at[i]);
  }
  Eigen::MatrixXd& G = g.G;
  Eigen::VectorXd& rhs = g.rhs;
  G.resize(2 * L, 2 * L);
  rhs.resize(2 * L);
  for (int i = 0; i < L; ++i) {
    rhs.segment<2>(2 * i) = B[i].transpose() * velocity[i];
    for (int j = 0; j < L; ++j) {
      G.block<2, 2>(2 * i, 2 * j) = P[i].transpose() * gaussian_hessian(at[i] - at[j], lambda) * P[j];
    }
  }
  G.diagonal().array() += 1e-13 * G.diagonal().maxCoeff();
  return g;
}

SphereField fit(const std::vector<Vector3d>& at, const std::vector<Vector3d>& velocity, double lambda) {
  const int L = static_cast<int>(at.size());
  const Gram g = gram(at, velocity, lambda);
  const std::vector<Eigen::Matrix<double, 3, 2>>& P = g.P;
  const Eigen::VectorXd a = detail::factor_gram(g.G, "sphere registration").solve(g.rhs);
  SphereField f;
  f.lambda = lambda;
  f.centres = at;
  f.weights.resize(L);
  for (int j = 0; j < L; ++j) f.weights[j] = P[j] * a.segment<2>(2 * j);
  return f;
}

// Leave-one-out error of the field fitted to the landmarks' first motion (each landmark's step
// toward its target predicted from the others').
double loo_error(const std::vector<Vector3d>& at, const std::vector<Vector3d>& velocity, double lambda) {
  const Gram g = gram(at, velocity, lambda);
  return detail::block_loo_error(g.G, g.rhs, "sphere registration");
}

// slerp(p, q, t) and its derivative (constant angular speed theta).
Vector3d great_circle(const Vector3d& p, const Vector3d& q, double t, Vector3d* velocity) {
  const double theta = std::atan2(p.cross(q).norm(), p.dot(q));
  if (theta < 1e-12) {
    if (velocity) *velocity = Vector3d::Zero();
    return p;
  }
  const double s = std::sin(theta);
  if (velocity) *velocity = theta * (-std::cos((1 - t) * theta) * p + std::cos(t * theta) * q) / s;
  return (std::sin((1 - t) * theta) * p + std::sin(t * theta) * q) / s;
}

SphereField field_at(const std::vector<Vector3d>& p, const std::vector<Vector3d>& q, double t, double lambda) {
  std::vector<Vector3d> at(p.size()), vel(p.size());
  for (size_t i = 0; i < p.size(); ++i) at[i] = great_circle(p[i], q[i], t, &vel[i]);
  return fit(at, vel, lambda);
}

std::vector<Vector3d> unit_rows(const Points& m, const char* what) {
  std::vector<Vector3d> v(m.rows());
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    const Vector3d x = m.row(i).transpose();
    if (!x.allFinite() || std::abs(x.norm() - 1) > 1e-4)
      throw InputError(std::string(what) + " " + std::to_string(i) + ": not on the unit sphere (|x| = " +
                       std::to_string(x.norm()) + "); register surfaces mapped by vpm map");
    v[i] = x.normalized();
  }
  return v;
}

// 1 on the corners of every face whose chord triangle the ray through a landmark crosses: the
// faces that carry the landmarks, held still by the restoration. A landmark at a vertex (given by
// its id) holds that vertex alone: holding its whole star too left slivers one ring further out
// that the repair could not mend (bench/results/LEDGER.md).
std::vector<char> landmark_corners(const std::vector<Vector3d>& x, const Triangles& f, const std::vector<Vector3d>& p) {
  std::vector<char> fixed(x.size(), 0);
  for (const Vector3d& d : p) {
    if (const size_t at = detail::vertex_at(x, d); at < x.size()) {
      fixed[at] = 1;
      continue;
    }
    for (Eigen::Index t = 0; t < f.rows(); ++t) {
      const Vector3d &a = x[f(t, 0)], &b = x[f(t, 1)], &c = x[f(t, 2)];
      if (d.dot(a + b + c) <= 0) continue;
      // d inside the cone over (a, b, c): on the same side of each of its three planes
      const double s0 = d.dot(a.cross(b)), s1 = d.dot(b.cross(c)), s2 = d.dot(c.cross(a));
      if ((s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0))
        for (int k = 0; k < 3; ++k) fixed[static_cast<size_t>(f(t, k))] = 1;
    }
  }
  return fixed;
}

// Mean angular distance of each point of `v` to its nearest other.
double mean_spacing(const std::vector<Vector3d>& v) {
  if (v.size() < 2) return M_PI / 2;
  double sum = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    double best = M_PI;
    for (size_t j = 0; j < v.size(); ++j)
      if (j != i) best = std::min(best, std::atan2(v[i].cross(v[j]).norm(), v[i].dot(v[j])));
    sum += best;
  }
  return sum / static_cast<double>(v.size());
}

}  // namespace

namespace {

// The landmark field's width factor chosen by leave-one-out on the landmarks' first motion.
double loo_width_factor(const std::vector<Vector3d>& p, const std::vector<Vector3d>& q, double spacing) {
  if (p.size() < 3) return kWidthFactors[0];
  std::vector<Vector3d> first(p.size());
  for (size_t i = 0; i < p.size(); ++i) first[i] = log_map(p[i], q[i]);
  double best = std::numeric_limits<double>::infinity(), chosen = kWidthFactors[0];
  for (double factor : kWidthFactors) {
    const double w = chord_width(factor, spacing), e = loo_error(p, first, 1 / (w * w));
    if (e < best) best = e, chosen = factor;
  }
  return chosen;
}

// Steps 3-4 from the rotated points x and landmarks p: the RK4 flow, then the last step onto the
// targets q. Fills res.points and the landmark errors.
void flow(Device& device, std::vector<Vector3d> x, const std::vector<Vector3d>& p, const std::vector<Vector3d>& q,
          double lambda, int steps, SurfaceRegistrationResult& res) {
  // the vertices and the landmarks (advected with them to measure the flow's error) in one call,
  // through the fields at the 2K + 1 stage times
  std::vector<DivFreeField> fields;
  for (int s = 0; s <= 2 * steps; ++s) fields.push_back(detail::carrier(field_at(p, q, s / (2.0 * steps), lambda)));
  std::vector<Vector3d> both = x;
  both.insert(both.end(), p.begin(), p.end());
  Points m = detail::to_matrix(both);
  detail::advect_on_sphere(device, m, fields, steps);
  for (size_t i = 0; i < x.size(); ++i) x[i] = m.row(static_cast<Eigen::Index>(i)).transpose();
  std::vector<Vector3d> moving(p.size());
  for (size_t i = 0; i < p.size(); ++i) moving[i] = m.row(static_cast<Eigen::Index>(x.size() + i)).transpose();
  // the last step: the field that carries each landmark's image onto its target, one exp step
  std::vector<Vector3d> rest(p.size());
  res.flow_landmark_max_error = res.landmark_max_error = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    rest[i] = log_map(moving[i], q[i]);
    res.flow_landmark_max_error = std::max(res.flow_landmark_max_error, (moving[i] - q[i]).norm());
  }
  const SphereField last = fit(moving, rest, lambda);
  detail::parallel_for(static_cast<int>(x.size()), 256, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) x[i] = exp_map(x[i], last(x[i])).normalized();
  });
  double sq = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const double e = (exp_map(moving[i], last(moving[i])) - q[i]).norm();
    sq += e * e;
    res.landmark_max_error = std::max(res.landmark_max_error, e);
  }
  res.landmark_rms_error = std::sqrt(sq / static_cast<double>(p.size()));
  res.points.resize(static_cast<Eigen::Index>(x.size()), 3);
  for (size_t i = 0; i < x.size(); ++i) res.points.row(static_cast<Eigen::Index>(i)) = x[i].transpose();
}

void check_inputs(const Points& landmarks, const Points& targets, const SurfaceRegistrationOptions& options, bool dense) {
  if (landmarks.rows() < 1 && !dense) throw InputError("sphere registration: no landmarks");
  if (landmarks.rows() != targets.rows())
    throw InputError("sphere registration: " + std::to_string(landmarks.rows()) + " landmarks but " +
                     std::to_string(targets.rows()) + " targets");
  if (options.steps < 1) throw InputError("sphere registration: steps must be at least 1");
  if (!(options.width_factor >= 0)) throw InputError("sphere registration: width_factor must be positive (or 0: chosen)");
}

}  // namespace

namespace {

// The landmark flow of steps 3-5 from x (rotated) carrying p onto q: the width factor given, or
// chosen by leave-one-out and, while the repair leaves faces flipped, the next narrower one.
void landmark_flow(Device& device, const std::vector<Vector3d>& x, const std::vector<Vector3d>& p, const std::vector<Vector3d>& q,
                   const Points& reference, const Triangles& faces, const detail::SurfaceDomainMoves& domain,
                   const SurfaceRegistrationOptions& options, SurfaceRegistrationResult& res) {
  const double spacing = std::min(mean_spacing(p), mean_spacing(q));
  res.width_factor = options.width_factor > 0 ? options.width_factor : loo_width_factor(p, q, spacing);
  while (true) {
    res.width = chord_width(res.width_factor, spacing);
    flow(device, x, p, q, 1 / (res.width * res.width), options.steps, res);
    res.flow_metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::sphere);
    res.repaired_faces = detail::repair_flips(domain, faces, detail::face_areas(reference, faces), res.points);
    const double* narrower = std::find(std::begin(kWidthFactors), std::end(kWidthFactors), res.width_factor);
    if (options.width_factor > 0 || domain.flipped(res.points, faces).empty() || narrower == std::begin(kWidthFactors) ||
        narrower == std::end(kWidthFactors))
      break;
    res.width_factor = *(narrower - 1);
  }
}

// Both registrations: `templ` null for landmarks alone.
SurfaceRegistrationResult run(const Points& sphere, const Triangles& faces, const Points& landmarks, const Points& targets,
                              const SurfaceRegistrationOptions& options, const Eigen::VectorXd* values,
                              const SphereTemplate* templ, Device* device) {
  const auto t0 = Clock::now();
  std::shared_ptr<Device> host;
  Device& dev = device ? *device : *(host = Device::host());
  check_inputs(landmarks, targets, options, templ != nullptr);
  if (templ) detail::check_match_options(options.match, "sphere registration");
  const std::vector<Vector3d> start = unit_rows(sphere, "vertex"), input_landmarks = unit_rows(landmarks, "landmark");
  std::vector<Vector3d> x = start, p = input_landmarks;
  const std::vector<Vector3d> q = unit_rows(targets, "target");
  SurfaceRegistrationResult res;
  if (options.rigid && p.size() >= 2) {
    Points pp(p.size(), 3), qq(q.size(), 3);
    for (size_t i = 0; i < p.size(); ++i) pp.row(i) = p[i].transpose(), qq.row(i) = q[i].transpose();
    res.rotation = kabsch_rotation(pp, qq);
  }
  for (auto& v : x) v = (res.rotation * v).normalized();
  for (auto& v : p) v = (res.rotation * v).normalized();
  for (size_t i = 0; i < p.size(); ++i)
    if (p[i].dot(q[i]) < -1 + 1e-12)
      throw InputError("sphere registration: landmark " + std::to_string(i) + " and its target are antipodal (after the rigid step)");
  Points reference(sphere.rows(), 3);
  for (size_t i = 0; i < start.size(); ++i) reference.row(static_cast<Eigen::Index>(i)) = start[i].transpose();
  const detail::SurfaceDomainMoves domain{SurfaceDomain::sphere, {}, landmark_corners(start, faces, input_landmarks)};
  if (!p.empty()) {
    landmark_flow(dev, x, p, q, reference, faces, domain, options, res);
  } else {
    res.points = reference;
    for (size_t i = 0; i < x.size(); ++i) res.points.row(static_cast<Eigen::Index>(i)) = x[i].transpose();
    res.flow_metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::sphere);
  }
  if (templ) {
    std::vector<Vector3d> moved = detail::unit_rows(res.points), carried = q;
    res.match = detail::match_on_sphere(dev, moved, carried, reference, faces, *values, *templ, options.match, domain);
    if (!p.empty()) {  // the landmarks back onto their targets from where the dense steps left them
      flow(dev, moved, carried, q, 1 / (res.width * res.width), options.steps, res);
      res.repaired_faces += detail::repair_flips(domain, faces, detail::face_areas(reference, faces), res.points);
    } else {
      for (size_t i = 0; i < moved.size(); ++i) res.points.row(static_cast<Eigen::Index>(i)) = moved[i].transpose();
    }
    res.flow_metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::sphere);
  }
  detail::restore_areas(domain, reference, faces, options, res);
  res.metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::sphere);
  res.seconds = seconds_since(t0);
  return res;
}

}  // namespace

SurfaceRegistrationResult register_on_sphere(const Points& sphere, const Triangles& faces, const Points& landmarks,
                                             const Points& targets, const SurfaceRegistrationOptions& options,
                                             Device* device) {
  return run(sphere, faces, landmarks, targets, options, nullptr, nullptr, device);
}

SurfaceRegistrationResult register_on_sphere(const Points& sphere, const Triangles& faces, const Eigen::VectorXd& values,
                                             const SphereTemplate& templ, const Points& landmarks, const Points& targets,
                                             const SurfaceRegistrationOptions& options, Device* device) {
  if (values.size() != sphere.rows())
    throw InputError("sphere registration: " + std::to_string(values.size()) + " values for " + std::to_string(sphere.rows()) + " vertices");
  if (templ.values.size() != templ.sphere.rows())
    throw InputError("sphere registration: the template has " + std::to_string(templ.values.size()) + " values for " +
                     std::to_string(templ.sphere.rows()) + " vertices");
  if (!values.allFinite() || !templ.values.allFinite()) throw InputError("sphere registration: a value is not finite");
  const std::vector<Vector3d> ts = unit_rows(templ.sphere, "template vertex");
  SphereTemplate t{Points(templ.sphere.rows(), 3), templ.faces, templ.values};
  for (size_t i = 0; i < ts.size(); ++i) t.sphere.row(static_cast<Eigen::Index>(i)) = ts[i].transpose();
  return run(sphere, faces, landmarks, targets, options, &values, &t, device);
}

}  // namespace vpm
