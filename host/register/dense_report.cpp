// Dense registration's names and its report's JSON (vpm/dense_registration.hpp).
#include "vpm/dense_registration.hpp"
#include "vpm/error.hpp"

namespace vpm {

const char* to_string(DenseForce f) {
  switch (f) {
    case DenseForce::labels: return "labels";
    case DenseForce::image: return "image";
    case DenseForce::both: return "both";
  }
  return "labels";
}

DenseForce dense_force_from_string(const std::string& w) {
  for (DenseForce f : {DenseForce::labels, DenseForce::image, DenseForce::both})
    if (w == to_string(f)) return f;
  throw InputError("dense force '" + w + "': expected labels, image or both");
}

Json to_json(const DenseIteration& it) {
  Json j = Json::object();
  j["width"] = it.width;
  j["matches"] = it.matches;
  j["centres"] = it.centres;
  j["mean_match_distance"] = it.mean_match_distance;
  j["max_move"] = it.max_move;
  j["agreement"] = it.agreement;
  if (it.mismatch >= 0) {
    j["mismatch"] = it.mismatch;
    j["image_points"] = it.image_points;
    j["mean_translation"] = it.mean_translation;
  }
  j["folded"] = it.folded;
  j["accepted"] = it.accepted;
  j["seconds"] = it.seconds;
  return j;
}

Json to_json(const DenseRefineReport& r) {
  Json j = Json::object();
  j["samples"] = r.samples;
  j["template_cells"] = r.template_cells;
  j["pinned_vertices"] = r.pinned_vertices;
  j["iterations"] = r.iterations;
  j["mismatch_before"] = r.mismatch_before;
  j["mismatch_after"] = r.mismatch_after;
  j["volume_before"] = r.volume_before;
  j["volume_after"] = r.volume_after;
  j["seconds"] = r.seconds;
  return j;
}

Json to_json(const DenseRegistrationResult& r) {
  Json j = Json::object();
  j["landmark"] = to_json(r.landmark);
  if (r.correction) j["correction"] = to_json(*r.correction);
  if (r.refine) j["refine"] = to_json(*r.refine);
  if (r.restore) j["restore"] = to_json(*r.restore);
  Json its = Json::array();
  for (const DenseIteration& it : r.iterations) its.push_back(to_json(it));
  j["iterations"] = its;
  Json regions = Json::array();
  for (int l : r.regions) regions.push_back(l);
  j["regions"] = regions;
  j["agreement_before"] = r.agreement_before;
  j["agreement_landmarks"] = r.agreement_landmarks;
  j["agreement_after"] = r.agreement_after;
  j["force"] = to_string(r.force);
  if (r.mismatch_before >= 0) {
    j["mismatch_before"] = r.mismatch_before;
    j["mismatch_landmarks"] = r.mismatch_landmarks;
    j["mismatch_after"] = r.mismatch_after;
  }
  j["landmark_rms_error"] = r.landmark_rms_error;
  j["landmark_max_error"] = r.landmark_max_error;
  j["max_normal_velocity"] = r.max_normal_velocity;
  j["inverted_tets"] = r.inverted_tets;
  j["stop_reason"] = r.time_budget_spent ? "time_budget" : "iterations";
  Json t = Json::object();
  t["landmark"] = r.seconds_landmark;
  t["dense"] = r.seconds_dense;
  t["correction"] = r.seconds_correction;
  if (r.refine) t["refine"] = r.seconds_refine;
  t["restore"] = r.seconds_restore;
  t["total"] = r.seconds_total;
  j["timings_s"] = t;
  return j;
}

}  // namespace vpm
