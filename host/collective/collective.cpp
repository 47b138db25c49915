#include "vpm/collective.hpp"

#include <cmath>
#include <limits>
#include <algorithm>
#include <set>
#include <unordered_map>

#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/locate.hpp"

namespace vpm {

std::vector<int> cell_labels(const TetMesh& mesh) {
  const Field* f = mesh.find_cell_field("label");
  if (!f || f->values.cols() != 1) throw InputError("mesh has no scalar cell field 'label'");
  std::vector<int> out(mesh.num_tets());
  for (int t = 0; t < mesh.num_tets(); ++t) out[t] = static_cast<int>(std::lround(f->values(t, 0)));
  return out;
}

Points label_centroids(const Points& vertices, const Tets& tets, const std::vector<int>& tet_labels,
                       const std::vector<int>& labels) {
  std::unordered_map<int, int> row;
  for (size_t i = 0; i < labels.size(); ++i) row.emplace(labels[i], static_cast<int>(i));
  Eigen::MatrixXd sum = Eigen::MatrixXd::Zero(labels.size(), 3);
  Eigen::VectorXd vol = Eigen::VectorXd::Zero(labels.size());
  const Eigen::VectorXd v = tet_volumes(vertices, tets);
  for (int t = 0; t < tets.rows(); ++t) {
    const auto it = row.find(tet_labels[t]);
    if (it == row.end()) continue;
    Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) c += vertices.row(tets(t, k));
    sum.row(it->second) += std::abs(v(t)) * 0.25 * c;
    vol(it->second) += std::abs(v(t));
  }
  Points out(labels.size(), 3);
  for (size_t i = 0; i < labels.size(); ++i)
    out.row(i) = vol(i) > 0 ? Eigen::RowVector3d(sum.row(i) / vol(i))
                            : Eigen::RowVector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return out;
}

RegionLandmarks region_landmarks(const TetMesh& moving, const TetMesh& fixed, const std::vector<int>& exclude) {
  const std::vector<int> lab_m = cell_labels(moving), lab_f = cell_labels(fixed);
  const std::set<int> in_m(lab_m.begin(), lab_m.end()), in_f(lab_f.begin(), lab_f.end());
  RegionLandmarks r;
  for (int l : in_m)
    if (l > 0 && in_f.count(l) && std::find(exclude.begin(), exclude.end(), l) == exclude.end()) r.labels.push_back(l);
  r.source = label_centroids(moving.vertices, moving.tets, lab_m, r.labels);
  r.target = label_centroids(fixed.vertices, fixed.tets, lab_f, r.labels);
  return r;
}

Points ball_grid_points(int per_axis) {
  if (per_axis < 1) throw InputError("ball grid: per_axis must be >= 1");
  const double h = 2.0 / per_axis;
  std::vector<Eigen::RowVector3d> pts;
  for (int k = 0; k < per_axis; ++k)
    for (int j = 0; j < per_axis; ++j)
      for (int i = 0; i < per_axis; ++i) {
        const Eigen::RowVector3d p(-1 + (i + 0.5) * h, -1 + (j + 0.5) * h, -1 + (k + 0.5) * h);
        if (p.squaredNorm() < 1) pts.push_back(p);
      }
  Points out(pts.size(), 3);
  for (size_t i = 0; i < pts.size(); ++i) out.row(i) = pts[i];
  return out;
}


}  // namespace vpm
