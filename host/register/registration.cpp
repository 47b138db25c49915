// The registration pipeline: input checks, rigid step, width and fields, advection, checks,
// volume restoration (one file each in host/register), and the report's JSON.
#include "vpm/registration.hpp"

#include <cmath>
#include <sstream>

#include "register/registration_steps.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"

namespace vpm {

RegistrationBoundary parse_registration_boundary(const std::string& t) {
  if (t == "tangent") return RegistrationBoundary::Tangent;
  if (t == "samples") return RegistrationBoundary::Samples;
  if (t == "none") return RegistrationBoundary::None;
  const std::string problem = "expected tangent, samples or none, got '" + t + "'";
  throw RegistrationInputError(RegistrationInputError::Subject::Option, "boundary: " + problem, -1, "boundary",
                               problem);
}
std::string to_string(RegistrationBoundary m) {
  return m == RegistrationBoundary::Tangent ? "tangent" : m == RegistrationBoundary::Samples ? "samples" : "none";
}
RegistrationField parse_registration_field(const std::string& t) {
  if (t == "per-step") return RegistrationField::PerStep;
  if (t == "steady") return RegistrationField::Steady;
  const std::string problem = "expected per-step or steady, got '" + t + "'";
  throw RegistrationInputError(RegistrationInputError::Subject::Option, "field: " + problem, -1, "field", problem);
}
std::string to_string(RegistrationField m) { return m == RegistrationField::PerStep ? "per-step" : "steady"; }

RegistrationSummary registration_summary(const RegistrationResult& result, const MapMetrics& against_before) {
  return {result.landmark_rms_error,          result.landmark_max_error,
          result.max_normal_velocity,         against_before.inverted_tets,
          against_before.vertex_volume_ratio, against_before.tet_volume_ratio,
          against_before.boundary_max_radius_error};
}

Json to_json(const RegistrationSummary& s) {
  Json r = Json::object();
  r["landmark_rms_error"] = s.landmark_rms_error;
  r["landmark_max_error"] = s.landmark_max_error;
  r["max_normal_velocity"] = s.max_normal_velocity;
  r["inverted_tets"] = s.inverted_tets;
  r["vertex_volume_ratio"] = to_json(s.vertex_volume_ratio);
  r["tet_volume_ratio"] = to_json(s.tet_volume_ratio);
  r["boundary_max_radius_error"] = s.boundary_max_radius_error;
  return r;
}

Json to_json(const RegistrationUntangle& u) {
  Json j = to_json(u.result);
  j["folded_by_flow"] = u.folded_by_flow;
  j["seconds"] = u.seconds;
  return j;
}

Json to_json(const RegistrationRestore& r) {
  Json j = Json::object();
  j["vertex_mean_abs_dev_before"] = r.vertex_mean_abs_dev_before;
  j["tet_mean_abs_dev_before"] = r.tet_mean_abs_dev_before;
  j["vertex_mean_abs_dev"] = r.vertex_mean_abs_dev;
  j["tet_mean_abs_dev"] = r.tet_mean_abs_dev;
  j["rounds"] = r.rounds;
  j["pinned_vertices"] = r.pinned_vertices;
  j["anchored_landmarks"] = r.anchored_landmarks;
  j["held_points"] = r.held_points;
  j["placement"] = to_json(r.placement);
  return j;
}

namespace {

Json to_json(const RegistrationTimings& t) {
  Json j = Json::object();
  j["rigid"] = t.rigid;
  j["fit"] = t.fit;
  j["advect"] = t.advect;
  j["check"] = t.check;
  if (t.restore) j["restore"] = *t.restore;
  j["total"] = t.total;
  return j;
}

Json to_json(const std::vector<WidthLooCandidate>& loo) {
  Json j = Json::array();
  for (const WidthLooCandidate& c : loo) {
    Json entry = Json::object();
    entry["width_factor"] = c.width_factor;
    entry["loo_rms"] = c.loo_rms;
    j.push_back(entry);
  }
  return j;
}

}  // namespace

Json to_json(const RegistrationResult& res) {
  const RegistrationReport& rep = res.report;
  Json r = Json::object();
  r["device"] = rep.device;
  r["vertices"] = rep.vertices;
  r["tets"] = rep.tets;
  r["landmarks"] = rep.landmarks;
  r["steps"] = rep.steps;
  r["lambda"] = res.lambda;
  r["width"] = rep.width;
  r["landmark_spacing"] = rep.landmark_spacing;
  if (!rep.width_loo.empty()) r["width_loo"] = to_json(rep.width_loo);
  r["boundary"] = to_string(rep.boundary);
  r["field"] = to_string(rep.field);
  r["rotation_deg"] = rep.rotation_deg;
  r["landmark_rms_error"] = res.landmark_rms_error;
  r["landmark_max_error"] = res.landmark_max_error;
  r["max_normal_velocity"] = res.max_normal_velocity;
  r["boundary_drift"] = res.boundary_drift;
  r["inverted_tets"] = res.inverted_tets;
  r["folded_by_flow"] = rep.folded_by_flow;
  if (rep.untangle) r["untangle"] = to_json(*rep.untangle);
  if (rep.restore) r["restore"] = to_json(*rep.restore);
  r["fit"] = to_json(rep.fit);
  r["timings_s"] = to_json(rep.timings);
  r["newly_inverted_tets"] = rep.newly_inverted_tets;
  return r;
}

namespace {

/// The mesh after the flow, checked: landmark errors, boundary drift and projection, normal
/// velocity, local untangling, fold counts (into `res`); volume restoration when fold-free.
Points check_and_restore(Device& dev, RegistrationResult& res, const Points& before, const Tets& tets,
                         Points after, const TetTopology& topology, const Points& landmarks,
                         const Points& targets, const std::vector<DivFreeField>& fields,
                         const RegistrationOptions& opt) {
  const std::vector<char>& boundary = topology.boundary_vertex;
  RegistrationReport& rep = res.report;
  auto t0 = Clock::now();
  measure_flow(res, after, boundary, targets, opt);
  res.max_normal_velocity = max_normal_velocity(dev, fields, opt.normal_check_samples);
  const Eigen::VectorXd v0 = tet_volumes(dev, before, tets);
  Eigen::VectorXd v1 = tet_volumes(dev, after, tets);
  const std::vector<char> landmark_vertex = landmark_vertices(before, landmarks);
  if (opt.untangle) {
    std::vector<char> fixed(boundary.begin(), boundary.end());
    for (size_t v = 0; v < fixed.size(); ++v) fixed[v] = fixed[v] || landmark_vertex[v];
    rep.untangle = untangle_flow_folds(dev, before, tets, after, fixed, v0, v1, opt.untangle_rings);
    if (rep.untangle) rep.folded_by_flow = rep.untangle->folded_by_flow;
  }
  for (Eigen::Index t = 0; t < v1.size(); ++t) {
    if (v1(t) <= 0) ++res.inverted_tets;
    if (v1(t) <= 0 && v0(t) > 0) ++rep.newly_inverted_tets;
  }
  rep.timings.check = seconds_since(t0);
  if (opt.restore_volumes && res.inverted_tets == 0) {
    t0 = Clock::now();
    rep.restore = restore_volumes(dev, {before, tets, topology}, after, landmark_vertex, res.landmarks_final, {}, opt);
    rep.timings.restore = seconds_since(t0);
  }
  return after;
}

[[noreturn]] void refuse_folds(const RegistrationResult& res, long tets, const RegistrationOptions& opt) {
  std::ostringstream s;
  s << "registration folded the mesh: " << res.report.newly_inverted_tets << " of " << tets << " tets inverted"
    << (opt.untangle ? " after local untangling" : "") << " (landmark rms error " << res.landmark_rms_error
    << ", width " << 1 / std::sqrt(res.lambda)
    << "): the landmark moves shear the flow more than these tets can follow; use smaller "
       "moves or a finer mesh";
  throw NumericalError(s.str());
}

}  // namespace

RegistrationResult register_landmarks(Device& dev, Points& ball, const Tets& tets, const Points& landmarks_in,
                                      const Points& targets, const RegistrationOptions& opt) {
  const auto t_start = Clock::now();
  const TetTopology topology = tet_topology(static_cast<int>(ball.rows()), tets);
  const std::vector<char>& boundary = topology.boundary_vertex;
  const std::vector<Eigen::Index> keep = check_registration_input(ball, boundary, landmarks_in, targets, opt);
  const Eigen::Index n = static_cast<Eigen::Index>(keep.size());
  Points p(n, 3), q(n, 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    p.row(i) = landmarks_in.row(keep[static_cast<size_t>(i)]);
    q.row(i) = targets.row(keep[static_cast<size_t>(i)]);
  }
  RegistrationResult res;
  RegistrationReport& rep = res.report;
  auto t0 = Clock::now();
  if (opt.rigid) res.rotation = kabsch_rotation(p, q);
  Points x(ball.rows() + landmarks_in.rows(), 3);
  x.topRows(ball.rows()) = ball * res.rotation.transpose();
  x.bottomRows(landmarks_in.rows()) = landmarks_in * res.rotation.transpose();
  p = p * res.rotation.transpose();
  rep.timings.rigid = seconds_since(t0);

  t0 = Clock::now();
  RegistrationWidth width = choose_width(p, q, opt);
  res.lambda = width.lambda;
  const std::vector<DivFreeField> fields = registration_fields(p, q, res.lambda, opt, &rep.fit);
  rep.timings.fit = seconds_since(t0);

  t0 = Clock::now();
  advect(dev, x, fields, opt.steps);
  rep.timings.advect = seconds_since(t0);

  res.landmarks_final = x.bottomRows(landmarks_in.rows());
  Points after = check_and_restore(dev, res, ball, tets, x.topRows(ball.rows()), topology, landmarks_in, targets,
                                   fields, opt);
  rep.timings.total = seconds_since(t_start);

  rep.device = dev.name();
  rep.vertices = static_cast<long>(ball.rows());
  rep.tets = static_cast<long>(tets.rows());
  rep.landmarks = static_cast<long>(landmarks_in.rows());
  rep.steps = opt.steps;
  rep.width = 1 / std::sqrt(res.lambda);
  rep.landmark_spacing = width.spacing;
  rep.width_loo = std::move(width.loo);
  rep.boundary = opt.boundary;
  rep.field = opt.field;
  rep.rotation_deg = rotation_degrees(res.rotation);
  if (rep.newly_inverted_tets > 0 && opt.refuse_folds) refuse_folds(res, static_cast<long>(tets.rows()), opt);
  ball = std::move(after);
  return res;
}

}  // namespace vpm
