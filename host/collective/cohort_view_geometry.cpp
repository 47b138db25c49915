// The canonical surfaces of the collective view (vpm/cohort_view.hpp): the display sphere's
// triangles assigned to element triangles, and the shells' surfaces and element centres pulled
// back to a subject's native space.
#include <cmath>

#include "vpm/cohort_view.hpp"
#include "vpm/error.hpp"
#include "vpm/sampling.hpp"

namespace vpm {

namespace {

std::vector<float> pull_back(const Points& ball, const TetMesh& registered) {
  const Points native = pull_back_points(ball, registered.vertices, registered.tets, native_positions(registered, "view: the registered mesh"));
  std::vector<float> out(static_cast<size_t>(native.rows()) * 3);
  for (Eigen::Index i = 0; i < native.rows(); ++i)
    for (int c = 0; c < 3; ++c) out[3 * i + c] = static_cast<float>(native(i, c));
  return out;
}

}  // namespace

std::vector<double> shell_mid_radii(const CanonicalElements& el) {
  std::vector<double> r(el.definition().shells);
  for (int k = 0; k < static_cast<int>(r.size()); ++k) r[k] = el.mid_radius(k);
  return r;
}

std::vector<int> display_triangle_elements(const CanonicalElements& el, const TriSurface& display) {
  std::vector<int> out(display.triangles.rows());
  const double r = shell_mid_radii(el).back();
  for (Eigen::Index f = 0; f < display.triangles.rows(); ++f) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v = 0; v < 3; ++v) c += display.vertices.row(display.triangles(f, v)).transpose();
    const int id = el.element_of(c.normalized() * r);
    if (id < 0) throw NumericalError("view: display triangle " + std::to_string(f) + " falls outside the ball");
    out[f] = el.triangle_of(id);
  }
  return out;
}

std::vector<float> native_shell_surfaces(const CanonicalElements& el, const TriSurface& display,
                                         const TetMesh& registered) {
  const std::vector<double> radii = shell_mid_radii(el);
  const Eigen::Index V = display.vertices.rows();
  Points ball(V * static_cast<Eigen::Index>(radii.size()), 3);
  for (size_t k = 0; k < radii.size(); ++k)
    ball.middleRows(static_cast<Eigen::Index>(k) * V, V) = display.vertices * radii[k];
  return pull_back(ball, registered);
}

std::vector<float> native_element_centres(const CanonicalElements& el, const TetMesh& registered) {
  Points ball(el.size(), 3);
  for (int e = 0; e < el.size(); ++e) ball.row(e) = el.centre(e).transpose();
  return pull_back(ball, registered);
}

}  // namespace vpm
