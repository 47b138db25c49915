// Area-preserving landmark registration in the unit disk (vpm/surface_registration.hpp,
// register_in_disk): straight pathlines, the divergence-free field tangent to the circle fitted
// to them at each RK4 stage, the last step onto the targets, the repair and the restoration.
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
#include "register/disk_field.hpp"
#include "register/disk_match.hpp"
#include "register/landmark_gram.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/surface_registration.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace {

using Eigen::Matrix2d;
using Eigen::Vector2d;
using detail::DiskField;
using detail::stream_hessian;

constexpr double kWidthFactors[] = {0.5, 1, 1.5, 2, 3, 4};
constexpr double kMaxRadius = 0.999;  // landmarks and targets strictly inside the disk

// G_ij = J M(y_i, y_j) J^T: symmetric positive definite (the kernel of a derivative of a
// positive definite kernel), so c = G^-1 u and b_j = J^T c_j interpolate.
Eigen::MatrixXd gram(const std::vector<Vector2d>& at, double lambda) {
  const int L = static_cast<int>(at.size());
  Eigen::MatrixXd G(2 * L, 2 * L);
  for (int i = 0; i < L; ++i)
    for (int j = 0; j < L; ++j) G.block<2, 2>(2 * i, 2 * j) = detail::quarter_turn() * stream_hessian(at[i], at[j], lambda) * detail::quarter_turn().transpose();
  G.diagonal().array() += 1e-13 * G.diagonal().maxCoeff();
  return G;
}

Eigen::VectorXd stacked(const std::vector<Vector2d>& u) {
  Eigen::VectorXd b(2 * static_cast<Eigen::Index>(u.size()));
  for (size_t i = 0; i < u.size(); ++i) b.segment<2>(2 * static_cast<Eigen::Index>(i)) = u[i];
  return b;
}

DiskField fit(const std::vector<Vector2d>& at, const std::vector<Vector2d>& velocity, double lambda) {
  const Eigen::VectorXd c = detail::factor_gram(gram(at, lambda), "disk registration").solve(stacked(velocity));
  DiskField f;
  f.lambda = lambda;
  f.centres = at;
  for (size_t j = 0; j < at.size(); ++j) f.weights.push_back(detail::quarter_turn().transpose() * c.segment<2>(2 * static_cast<Eigen::Index>(j)));
  return f;
}

// Rippa's leave-one-out error with 2 x 2 blocks (as on the sphere).
double loo_error(const std::vector<Vector2d>& at, const std::vector<Vector2d>& velocity, double lambda) {
  return detail::block_loo_error(gram(at, lambda), stacked(velocity), "disk registration");
}

double mean_spacing(const std::vector<Vector2d>& v) {
  if (v.size() < 2) return 1;
  double sum = 0;
  for (size_t i = 0; i < v.size(); ++i) {
    double best = std::numeric_limits<double>::infinity();
    for (size_t j = 0; j < v.size(); ++j)
      if (j != i) best = std::min(best, (v[i] - v[j]).norm());
    sum += best;
  }
  return sum / static_cast<double>(v.size());
}

double loo_width_factor(const std::vector<Vector2d>& p, const std::vector<Vector2d>& q, double spacing) {
  if (p.size() < 3) return kWidthFactors[0];
  std::vector<Vector2d> first(p.size());
  for (size_t i = 0; i < p.size(); ++i) first[i] = q[i] - p[i];
  double best = std::numeric_limits<double>::infinity(), chosen = kWidthFactors[0];
  for (double factor : kWidthFactors) {
    const double w = factor * spacing, e = loo_error(p, first, 1 / (w * w));
    if (e < best) best = e, chosen = factor;
  }
  return chosen;
}

DiskField field_at(const std::vector<Vector2d>& p, const std::vector<Vector2d>& q, double t, double lambda) {
  std::vector<Vector2d> at(p.size()), vel(p.size());
  for (size_t i = 0; i < p.size(); ++i) at[i] = (1 - t) * p[i] + t * q[i], vel[i] = q[i] - p[i];
  return fit(at, vel, lambda);
}

// The RK4 flow of every vertex along the landmarks' straight pathlines (on `device`), then one
// step of the field that carries the landmarks' images exactly onto their targets. Fills
// res.points and the landmark errors.
void flow(Device& device, std::vector<Vector2d> x, const std::vector<char>& boundary, const std::vector<Vector2d>& p,
          const std::vector<Vector2d>& q, double lambda, int steps, SurfaceRegistrationResult& res) {
  // the vertices and the landmarks (advected with them to measure the flow's error) in one call,
  // through the fields at the 2K + 1 stage times
  std::vector<DivFreeField> fields;
  for (int s = 0; s <= 2 * steps; ++s) fields.push_back(detail::disk_carrier(field_at(p, q, s / (2.0 * steps), lambda)));
  const size_t n = x.size();
  x.insert(x.end(), p.begin(), p.end());
  detail::advect_in_disk(device, x, fields, steps, boundary);
  const std::vector<Vector2d> moving(x.begin() + static_cast<std::ptrdiff_t>(n), x.end());
  x.resize(n);
  std::vector<Vector2d> rest(p.size());
  res.flow_landmark_max_error = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    rest[i] = q[i] - moving[i];
    res.flow_landmark_max_error = std::max(res.flow_landmark_max_error, rest[i].norm());
  }
  const DiskField last = fit(moving, rest, lambda);
  for (Vector2d& v : x) v += last(v);
  detail::place_in_disk(x, boundary);
  double sq = 0;
  res.landmark_max_error = 0;
  for (size_t i = 0; i < p.size(); ++i) {
    const double e = (moving[i] + last(moving[i]) - q[i]).norm();
    sq += e * e;
    res.landmark_max_error = std::max(res.landmark_max_error, e);
  }
  res.landmark_rms_error = std::sqrt(sq / static_cast<double>(p.size()));
  res.points = detail::disk_points(x);
}

// 1 on the corners of the faces that contain a landmark (held still by the restoration).
std::vector<char> landmark_corners(const std::vector<Vector2d>& x, const Triangles& f, const std::vector<Vector2d>& p) {
  std::vector<char> fixed(x.size(), 0);
  auto cross = [](const Vector2d& a, const Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); };
  for (const Vector2d& d : p) {
    if (const size_t at = detail::vertex_at(x, d); at < x.size()) {  // a landmark at a vertex: that vertex alone
      fixed[at] = 1;
      continue;
    }
    for (Eigen::Index t = 0; t < f.rows(); ++t) {
      const Vector2d &a = x[static_cast<size_t>(f(t, 0))], &b = x[static_cast<size_t>(f(t, 1))], &c = x[static_cast<size_t>(f(t, 2))];
      if (cross(b - a, d - a) >= 0 && cross(c - b, d - b) >= 0 && cross(a - c, d - c) >= 0)
        for (int k = 0; k < 3; ++k) fixed[static_cast<size_t>(f(t, k))] = 1;
    }
  }
  return fixed;
}

std::vector<Vector2d> disk_rows(const Points& m, const char* what, double max_radius) {
  std::vector<Vector2d> v(static_cast<size_t>(m.rows()));
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    const Vector2d x(m(i, 0), m(i, 1));
    if (!m.row(i).allFinite() || std::abs(m(i, 2)) > 1e-6 || x.norm() > max_radius)
      throw InputError(std::string(what) + " " + std::to_string(i) + ": not " +
                       (max_radius < 1 ? "strictly inside the unit disk" : "in the unit disk (z = 0, |x| <= 1)") +
                       "; register surfaces mapped to the disk by vpm map");
    v[static_cast<size_t>(i)] = x;
  }
  return v;
}

// The rotation about the centre that best maps p onto q (2-D Kabsch).
double best_angle(const std::vector<Vector2d>& p, const std::vector<Vector2d>& q) {
  double s = 0, c = 0;
  for (size_t i = 0; i < p.size(); ++i) c += p[i].dot(q[i]), s += p[i].x() * q[i].y() - p[i].y() * q[i].x();
  return std::atan2(s, c);
}

}  // namespace

namespace {

void check_inputs(const Points& landmarks, const Points& targets, const SurfaceRegistrationOptions& options, bool dense) {
  if (landmarks.rows() < 1 && !dense) throw InputError("disk registration: no landmarks");
  if (landmarks.rows() != targets.rows())
    throw InputError("disk registration: " + std::to_string(landmarks.rows()) + " landmarks but " + std::to_string(targets.rows()) + " targets");
  if (options.steps < 1) throw InputError("disk registration: steps must be at least 1");
  if (!(options.width_factor >= 0)) throw InputError("disk registration: width_factor must be positive (or 0: chosen)");
}

// The landmark flow from x (rotated) carrying p onto q: the width factor given, or chosen by
// leave-one-out and, while the repair leaves faces flipped, the next narrower one.
void landmark_flow(Device& device, const std::vector<Vector2d>& x, const std::vector<Vector2d>& p, const std::vector<Vector2d>& q, const Points& reference,
                   const Triangles& faces, const detail::SurfaceDomainMoves& domain, const SurfaceRegistrationOptions& options,
                   SurfaceRegistrationResult& res) {
  const double spacing = std::min(mean_spacing(p), mean_spacing(q));
  res.width_factor = options.width_factor > 0 ? options.width_factor : loo_width_factor(p, q, spacing);
  while (true) {
    res.width = res.width_factor * spacing;
    flow(device, x, domain.boundary, p, q, 1 / (res.width * res.width), options.steps, res);
    res.flow_metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::disk);
    res.repaired_faces = detail::repair_flips(domain, faces, detail::face_areas(reference, faces), res.points);
    const double* narrower = std::find(std::begin(kWidthFactors), std::end(kWidthFactors), res.width_factor);
    if (options.width_factor > 0 || domain.flipped(res.points, faces).empty() || narrower == std::begin(kWidthFactors) ||
        narrower == std::end(kWidthFactors))
      break;
    res.width_factor = *(narrower - 1);
  }
}

// Both registrations: `templ` null for landmarks alone.
SurfaceRegistrationResult run(const Points& disk, const Triangles& faces, const Points& landmarks, const Points& targets,
                              const SurfaceRegistrationOptions& options, const Eigen::VectorXd* values, const DiskTemplate* templ,
                              Device* device) {
  const auto t0 = Clock::now();
  std::shared_ptr<Device> host;
  Device& dev = device ? *device : *(host = Device::host());
  check_inputs(landmarks, targets, options, templ != nullptr);
  if (templ) detail::check_match_options(options.match, "disk registration");
  const std::vector<Vector2d> start = disk_rows(disk, "vertex", 1 + 1e-6), input_landmarks = disk_rows(landmarks, "landmark", kMaxRadius);
  const std::vector<Vector2d> q = disk_rows(targets, "target", kMaxRadius);
  const Points reference = detail::disk_points(start);
  const detail::SurfaceDomainMoves domain{SurfaceDomain::disk, detail::loop_mask(static_cast<int>(disk.rows()), faces),
                                          landmark_corners(start, faces, input_landmarks)};
  SurfaceRegistrationResult res;
  const double angle = options.rigid && input_landmarks.size() >= 2 ? best_angle(input_landmarks, q) : 0;
  res.rotation = Eigen::AngleAxisd(angle, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Rotation2Dd R(angle);
  std::vector<Vector2d> x = start, p = input_landmarks;
  for (auto& v : x) v = R * v;
  for (auto& v : p) v = R * v;
  if (!p.empty()) {
    landmark_flow(dev, x, p, q, reference, faces, domain, options, res);
  } else {
    res.points = detail::disk_points(x);
    res.flow_metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::disk);
  }
  if (templ) {
    std::vector<Vector2d> moved = detail::disk_vectors(res.points), carried = q;
    res.match = detail::match_in_disk(dev, moved, carried, reference, faces, *values, *templ, options.match, domain);
    if (!p.empty()) {  // the landmarks back onto their targets from where the dense steps left them
      flow(dev, moved, domain.boundary, carried, q, 1 / (res.width * res.width), options.steps, res);
      res.repaired_faces += detail::repair_flips(domain, faces, detail::face_areas(reference, faces), res.points);
    } else {
      res.points = detail::disk_points(moved);
    }
    res.flow_metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::disk);
  }
  detail::restore_areas(domain, reference, faces, options, res);
  res.metrics = surface_metrics(reference, res.points, faces, SurfaceDomain::disk);
  res.seconds = seconds_since(t0);
  return res;
}

}  // namespace

SurfaceRegistrationResult register_in_disk(const Points& disk, const Triangles& faces, const Points& landmarks,
                                           const Points& targets, const SurfaceRegistrationOptions& options, Device* device) {
  return run(disk, faces, landmarks, targets, options, nullptr, nullptr, device);
}

SurfaceRegistrationResult register_in_disk(const Points& disk, const Triangles& faces, const Eigen::VectorXd& values,
                                           const DiskTemplate& templ, const Points& landmarks, const Points& targets,
                                           const SurfaceRegistrationOptions& options, Device* device) {
  if (values.size() != disk.rows())
    throw InputError("disk registration: " + std::to_string(values.size()) + " values for " + std::to_string(disk.rows()) + " vertices");
  if (templ.values.size() != templ.disk.rows())
    throw InputError("disk registration: the template has " + std::to_string(templ.values.size()) + " values for " +
                     std::to_string(templ.disk.rows()) + " vertices");
  if (!values.allFinite() || !templ.values.allFinite()) throw InputError("disk registration: a value is not finite");
  const DiskTemplate t{detail::disk_points(disk_rows(templ.disk, "template vertex", 1 + 1e-6)), templ.faces, templ.values};
  return run(disk, faces, landmarks, targets, options, &values, &t, device);
}

}  // namespace vpm
