// ---- checks after the flow: landmark errors, boundary drift, normal velocity, folds ----
#include <algorithm>
#include <cmath>

#include "register/registration_steps.hpp"
#include "vpm/geometry.hpp"
#include "vpm/timing.hpp"

namespace vpm {

void measure_flow(RegistrationResult& res, Points& after, const std::vector<char>& boundary,
                  const Points& targets, const RegistrationOptions& opt) {
  const Eigen::VectorXd err = (res.landmarks_final - targets).rowwise().norm();
  res.landmark_rms_error = std::sqrt(err.squaredNorm() / static_cast<double>(err.size()));
  res.landmark_max_error = err.maxCoeff();
  for (Eigen::Index v = 0; v < after.rows(); ++v) {
    if (!boundary[static_cast<size_t>(v)]) continue;
    const double r = after.row(v).norm();
    res.boundary_drift = std::max(res.boundary_drift, std::fabs(r - 1));
    if (opt.project_boundary && r > 0) after.row(v) /= r;
  }
}

double max_normal_velocity(Device& dev, const std::vector<DivFreeField>& fields, int samples) {
  const Points sphere = fibonacci_sphere(samples);
  const size_t nf = fields.size();
  const size_t stride = std::max<size_t>(1, nf / 10);
  std::vector<size_t> check_slots;
  for (size_t s = 0; s < nf; s += stride) check_slots.push_back(s);
  if (check_slots.back() != nf - 1) check_slots.push_back(nf - 1);
  double worst = 0;
  for (size_t s : check_slots) {
    const Points u = evaluate(dev, fields[s], sphere);
    worst = std::max(worst, (u.array() * sphere.array()).rowwise().sum().abs().maxCoeff());
  }
  return worst;
}

std::vector<char> landmark_vertices(const Points& before, const Points& landmarks) {
  std::vector<char> landmark_vertex(static_cast<size_t>(before.rows()), 0);
  for (Eigen::Index v = 0; v < before.rows(); ++v)
    for (Eigen::Index i = 0; i < landmarks.rows(); ++i)
      if ((before.row(v) - landmarks.row(i)).squaredNorm() <= 1e-24) landmark_vertex[static_cast<size_t>(v)] = 1;
  return landmark_vertex;
}

std::optional<RegistrationUntangle> untangle_flow_folds(Device& dev, const Points& before, const Tets& tets,
                                                        Points& after, const std::vector<char>& fixed,
                                                        const Eigen::VectorXd& v0, Eigen::VectorXd& v1,
                                                        int rings) {
  std::vector<int> folded;
  for (Eigen::Index t = 0; t < v1.size(); ++t)
    if (v1(t) <= 0 && v0(t) > 0) folded.push_back(static_cast<int>(t));
  if (folded.empty()) return std::nullopt;
  const auto t0 = Clock::now();
  RegistrationUntangle u;
  u.result = untangle_local(before, tets, after, fixed, folded, rings, untangle_local_options());
  u.folded_by_flow = static_cast<int>(folded.size());
  u.seconds = seconds_since(t0);
  v1 = tet_volumes(dev, after, tets);
  return u;
}

}  // namespace vpm
