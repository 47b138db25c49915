#include "vpm/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "vpm/device.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

namespace vpm {

RatioStats ratio_stats(const Eigen::VectorXd& r) {
  RatioStats s;
  const Eigen::Index n = r.size();
  if (n == 0) return s;
  std::vector<double> abslog(static_cast<size_t>(n));
  double sum_abs = 0, sum_log = 0, sum_log2 = 0;
  s.min = r.minCoeff();
  s.max = r.maxCoeff();
  for (Eigen::Index i = 0; i < n; ++i) {
    sum_abs += std::fabs(r(i) - 1.0);
    const double l = std::log(std::max(r(i), 1e-300));
    sum_log += l;
    sum_log2 += l * l;
    abslog[static_cast<size_t>(i)] = std::fabs(l);
  }
  s.mean_abs_dev = sum_abs / static_cast<double>(n);
  const double mean = sum_log / static_cast<double>(n);
  s.std_log = std::sqrt(std::max(0.0, sum_log2 / static_cast<double>(n) - mean * mean));
  const size_t k = std::min(static_cast<size_t>(std::ceil(0.99 * static_cast<double>(n))) - 1, abslog.size() - 1);
  std::nth_element(abslog.begin(), abslog.begin() + static_cast<std::ptrdiff_t>(k), abslog.end());
  s.p99_abs_log = abslog[k];  // the k-th smallest, as a full sort would place it
  s.max_abs_log = *std::max_element(abslog.begin() + static_cast<std::ptrdiff_t>(k), abslog.end());
  return s;
}

void volume_ratios(const Eigen::VectorXd& v0, const Eigen::VectorXd& v1, const Tets& tets, Eigen::Index n,
                   Eigen::VectorXd& tet_ratio, Eigen::VectorXd& vertex_ratio) {
  const double s0 = v0.sum(), s1 = v1.sum();
  tet_ratio = (v1 / s1).array() / (v0 / s0).array();
  Eigen::VectorXd d0 = Eigen::VectorXd::Zero(n), d1 = Eigen::VectorXd::Zero(n);
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int c = 0; c < 4; ++c) {
      d0(tets(t, c)) += 0.25 * v0(t);
      d1(tets(t, c)) += 0.25 * v1(t);
    }
  vertex_ratio = (d1 / s1).array() / (d0 / s0).array();
}

DistortionPair volume_distortion(const Points& ref, const Points& x, const Tets& tets) {
  const Eigen::VectorXd v0 = tet_volumes(ref, tets), v1 = tet_volumes(x, tets);
  Eigen::VectorXd tr, vr;
  volume_ratios(v0, v1, tets, ref.rows(), tr, vr);
  DistortionPair d;
  for (Eigen::Index t = 0; t < tr.size(); ++t) {
    d.tet += std::fabs(tr(t) - 1.0);
    d.folds += v1(t) <= 0;
  }
  int used = 0;
  for (Eigen::Index i = 0; i < vr.size(); ++i)
    if (!std::isnan(vr(i))) {
      d.vertex += std::fabs(vr(i) - 1.0);
      ++used;
    }
  d.tet /= std::max<Eigen::Index>(1, tets.rows());
  d.vertex /= std::max(1, used);
  return d;
}

MapMetrics map_metrics(Device& dev, const Points& ref, const Points& mapped, const Tets& tets,
                       const std::vector<char>* boundary_mask) {
  MapMetrics m;
  const Eigen::VectorXd v0 = tet_volumes(dev, ref, tets);
  const Eigen::VectorXd v1 = tet_volumes(dev, mapped, tets);
  m.inverted_tets = static_cast<int>((v1.array() <= 0).count());
  volume_ratios(v0, v1, tets, ref.rows(), m.tet_ratio, m.vertex_ratio);
  m.tet_volume_ratio = ratio_stats(m.tet_ratio);
  m.vertex_volume_ratio = ratio_stats(m.vertex_ratio);
  std::vector<char> own;
  if (!boundary_mask || boundary_mask->size() != static_cast<size_t>(mapped.rows())) {
    own = boundary_vertex_mask(static_cast<int>(mapped.rows()), boundary_faces(tets));
    boundary_mask = &own;
  }
  for (Eigen::Index i = 0; i < mapped.rows(); ++i)
    if ((*boundary_mask)[static_cast<size_t>(i)])
      m.boundary_max_radius_error =
          std::max(m.boundary_max_radius_error, std::fabs(mapped.row(i).norm() - 1.0));
  return m;
}

Json to_json(const RatioStats& s) {
  Json j = Json::object();
  j["mean_abs_dev"] = s.mean_abs_dev;
  j["std_log"] = s.std_log;
  j["p99_abs_log"] = s.p99_abs_log;
  j["max_abs_log"] = s.max_abs_log;
  j["min"] = s.min;
  j["max"] = s.max;
  return j;
}

Json to_json(const MapMetrics& m) {
  Json j = Json::object();
  j["inverted_tets"] = m.inverted_tets;
  j["vertex_volume_ratio"] = to_json(m.vertex_volume_ratio);
  j["tet_volume_ratio"] = to_json(m.tet_volume_ratio);
  j["boundary_max_radius_error"] = m.boundary_max_radius_error;
  return j;
}

}  // namespace vpm
