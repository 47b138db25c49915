// The ideal registration (ideal.hpp).
#include "pairs/ideal.hpp"

#include <algorithm>
#include <vector>

#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/locate.hpp"
#include "vpm/topology.hpp"

namespace vpm::bench {

IdealRegistration ideal_registration(const TetMesh& subject, const TetMesh& tmpl,
                                     const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull) {
  const Points native = native_positions(subject, "demo: the subject's ball map");
  const Points tnative = native_positions(tmpl, "demo: colin27's ball map");
  const TetLocator locator(tnative, tmpl.tets);
  IdealRegistration r;
  r.ball.resize(native.rows(), 3);
  int hint = -1;
  for (Eigen::Index i = 0; i < native.rows(); ++i) {
    const Location l = locator.locate(pull(native.row(i).transpose()), hint);
    r.outside += !l.inside();
    if (l.tet < 0) {  // not located at all (cannot happen on a valid mesh): left where it is
      r.ball.row(i) = subject.vertices.row(i);
      continue;
    }
    hint = l.tet;
    double sum = 0;
    Eigen::RowVector3d x = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) {  // outside: the nearest tet's clamped coordinates, renormalised
      x += l.bary[k] * tmpl.vertices.row(tmpl.tets(l.tet, k));
      sum += l.bary[k];
    }
    r.ball.row(i) = x / sum;
  }
  // the subject's surface goes onto the sphere, as every registration in the ball keeps it
  const std::vector<char> boundary = boundary_vertex_mask(static_cast<int>(native.rows()), boundary_faces(subject.tets));
  for (Eigen::Index i = 0; i < native.rows(); ++i)
    if (boundary[static_cast<size_t>(i)]) {
      r.ball.row(i).normalize();
      ++r.boundary;
    }
  return r;
}

IdealReport measure_ideal(Device& device, const TetMesh& subject, const TetMesh& tmpl, const Points& registered,
                          const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull,
                          const std::function<Overlap(const Points&)>& overlap_of) {
  IdealReport r;
  r.ideal = ideal_registration(subject, tmpl, pull);
  r.overlap = overlap_of(r.ideal.ball);
  r.metrics = map_metrics(device, subject.vertices, r.ideal.ball, subject.tets);
  r.error = (registered - r.ideal.ball).rowwise().norm();
  std::vector<double> e(r.error.data(), r.error.data() + r.error.size());
  if (!e.empty()) {
    for (double x : e) r.error_mean += x / static_cast<double>(e.size());
    std::sort(e.begin(), e.end());
    r.error_p90 = e[static_cast<size_t>(0.9 * static_cast<double>(e.size() - 1))];
    r.error_max = e.back();
  }
  return r;
}

Json to_json(const IdealReport& r, const std::vector<int>& evaluated) {
  Json j = Json::object();
  Json held = Json::array();
  for (size_t i = 0; i < evaluated.size() && i < r.overlap.image_after.size(); ++i) {
    Json o = Json::object();
    o["label"] = evaluated[i];
    o["dice_image"] = r.overlap.image_after[i].dice;
    o["dice_subject"] = r.overlap.subject_after[i].dice;
    held.push_back(o);
  }
  j["held_out"] = held;
  j["landmark_regions_mean_dice_image"] = r.overlap.image_landmark_after;
  j["vertex_volume_ratio"] = to_json(r.metrics.vertex_volume_ratio);
  j["tet_volume_ratio"] = to_json(r.metrics.tet_volume_ratio);
  j["inverted_tets"] = r.metrics.inverted_tets;
  j["outside_vertices"] = r.ideal.outside;
  j["boundary_vertices"] = r.ideal.boundary;
  Json e = Json::object();
  e["mean"] = r.error_mean;
  e["p90"] = r.error_p90;
  e["max"] = r.error_max;
  j["error_to_ideal"] = e;
  return j;
}

std::string ideal_summary(const IdealReport& r) {
  std::string dice;
  for (const LabelOverlap& o : r.overlap.image_after) dice += (dice.empty() ? "" : " / ") + strprintf("%.3f", o.dice);
  std::string subject;
  for (const LabelOverlap& o : r.overlap.subject_after)
    subject += (subject.empty() ? "" : " / ") + strprintf("%.3f", o.dice);
  return "ideal registration (from the known deformation): held-out Dice " + dice + " (in the subject's space " +
         subject + ")" +
         ";\nthis registration's vertices are off it by " + strprintf("%.4f", r.error_mean) +
         " ball units on average (p90 " + strprintf("%.4f", r.error_p90) + ")\n";
}

}  // namespace vpm::bench
