// The JSON form of a registration on the sphere (vpm/surface_registration.hpp).
#include <Eigen/Geometry>
#include <cmath>

#include "vpm/surface_registration.hpp"

namespace vpm {

Json to_json(const SurfaceRegistrationResult& r, const SurfaceRegistrationOptions& options) {
  Json j = Json::object();
  j["steps"] = options.steps;
  j["width"] = r.width;
  j["width_factor"] = r.width_factor;
  j["rotation_angle_deg"] = Eigen::AngleAxisd(r.rotation).angle() * 180 / M_PI;
  j["landmark_rms_error"] = r.landmark_rms_error;
  j["landmark_max_error"] = r.landmark_max_error;
  j["flow_landmark_max_error"] = r.flow_landmark_max_error;
  j["flow"] = to_json(r.flow_metrics);
  j["restore"] = Json::object();
  j["restore"]["rounds"] = r.restore_rounds;
  j["restore"]["held_vertices"] = r.held_vertices;
  j["restore"]["repaired_faces"] = r.repaired_faces;
  j["final"] = to_json(r.metrics);
  if (!r.match.levels.empty()) {
    Json m = Json::object();
    m["correlation_before"] = r.match.correlation_before;
    m["correlation_after"] = r.match.correlation_after;
    m["levels"] = Json::array();
    for (const SphereMatchLevel& l : r.match.levels) {
      Json o = Json::object();
      o["width"] = l.width;
      o["centres"] = l.centres;
      o["iterations"] = l.iterations;
      o["reliefs"] = l.reliefs;
      o["mismatch_before"] = l.mismatch_before;
      o["mismatch_after"] = l.mismatch_after;
      m["levels"].push_back(o);
    }
    if (r.match.rotation_searched) {
      Json s = Json::object();
      s["correlation_identity"] = r.match.search_correlation_identity;
      s["correlation_best"] = r.match.search_correlation_best;
      s["angle_deg"] = Eigen::AngleAxisd(r.match.rotation).angle() * 180 / M_PI;
      m["rotation_search"] = s;
    }
    m["seconds"] = r.match.seconds;
    j["match"] = m;
  }
  j["timings_s"] = Json::object();
  j["timings_s"]["total"] = r.seconds;
  return j;
}

}  // namespace vpm
