// ---- input checks of register_landmarks ----
#include <cmath>
#include <sstream>

#include "register/registration_steps.hpp"

namespace vpm {

namespace {

constexpr double kOutsideTolerance = 1e-9;  // |p| > 1 + this: outside the ball
constexpr double kSphereTolerance = 1e-6;   // | |p| - 1 | <= this: on the boundary sphere
constexpr double kDuplicateDistance = 1e-9;

using Subject = RegistrationInputError::Subject;

std::string fmt3(const Eigen::Vector3d& p) {
  std::ostringstream s;
  s.precision(6);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ")";
  return s.str();
}

void check_counts(const Points& landmarks, const Points& targets, const RegistrationOptions& opt) {
  if (landmarks.rows() != targets.rows())
    throw RegistrationInputError(Subject::Landmarks, "landmarks: " + std::to_string(landmarks.rows()) +
                                                         " landmarks but " + std::to_string(targets.rows()) +
                                                         " targets");
  if (landmarks.rows() == 0) throw RegistrationInputError(Subject::Landmarks, "landmarks: no landmarks given");
  if (opt.steps < 1)
    throw RegistrationInputError(Subject::Option, "steps: must be at least 1", -1, "steps", "must be at least 1");
  if (opt.lambda < 0 || !std::isfinite(opt.lambda))
    throw RegistrationInputError(Subject::Option, "lambda: must be >= 0", -1, "lambda", "must be >= 0");
  if (opt.restore_iterations < 1 || opt.restore_rounds < 0)
    throw RegistrationInputError(Subject::Option, "restore-iterations: must be at least 1 (and rounds >= 0)", -1,
                                 "restore-iterations", "must be at least 1 (and rounds >= 0)");
}

/// The landmark / target pair at row i on its own: finite, inside the ball, both on the
/// sphere or both inside.
void check_pair(Eigen::Index i, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const int row = static_cast<int>(i);
  const std::string who = "landmark " + std::to_string(i + 1);
  auto refuse = [&](const std::string& message) { throw RegistrationInputError(Subject::Landmark, message, row); };
  if (!p.allFinite() || !q.allFinite()) refuse(who + ": non-finite coordinate");
  if (p.norm() > 1 + kOutsideTolerance)
    refuse(who + " " + fmt3(p) + " is outside the unit ball (|p| = " + std::to_string(p.norm()) + ")");
  if (q.norm() > 1 + kOutsideTolerance)
    refuse(who + ": target " + fmt3(q) + " is outside the unit ball (|q| = " + std::to_string(q.norm()) + ")");
  const bool pb = std::fabs(p.norm() - 1) <= kSphereTolerance;
  const bool qb = std::fabs(q.norm() - 1) <= kSphereTolerance;
  if (pb != qb)
    refuse(who + ": " + (pb ? "the landmark" : "the target") + " lies on the boundary sphere but " +
           (pb ? "its target" : "the landmark") + " does not; the registration keeps the sphere on itself");
}

void check_mapped(const Points& ball, const std::vector<char>& boundary) {
  for (Eigen::Index v = 0; v < ball.rows(); ++v)
    if (boundary[static_cast<size_t>(v)] && std::fabs(ball.row(v).norm() - 1) > kSphereTolerance) {
      std::ostringstream s;
      s << "mesh is not mapped to the unit ball: boundary vertex " << v << " has radius " << ball.row(v).norm();
      throw RegistrationInputError(Subject::Mesh, s.str());
    }
}

}  // namespace

std::vector<Eigen::Index> check_registration_input(const Points& ball, const std::vector<char>& boundary,
                                                   const Points& landmarks, const Points& targets,
                                                   const RegistrationOptions& opt) {
  check_counts(landmarks, targets, opt);
  std::vector<Eigen::Index> keep;
  for (Eigen::Index i = 0; i < landmarks.rows(); ++i) {
    const Eigen::Vector3d p = landmarks.row(i).transpose(), q = targets.row(i).transpose();
    check_pair(i, p, q);
    bool duplicate = false;
    for (Eigen::Index j : keep) {
      if ((landmarks.row(j) - landmarks.row(i)).norm() > kDuplicateDistance) continue;
      if ((targets.row(j) - targets.row(i)).norm() > kDuplicateDistance)
        throw RegistrationInputError(Subject::Landmark,
                                     "landmark " + std::to_string(i + 1) + " " + fmt3(p) + " repeats landmark " +
                                         std::to_string(j + 1) + " with a different target",
                                     static_cast<int>(i));
      duplicate = true;
    }
    if (!duplicate) keep.push_back(i);
  }
  check_mapped(ball, boundary);
  return keep;
}

}  // namespace vpm
