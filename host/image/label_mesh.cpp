// Atlas labels on a tet mesh (vpm/mesh_image.hpp label_mesh) and mesh_image()'s label report.
#include "image/label_mesh.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <vector>

#include "vpm/geometry.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/topology.hpp"

namespace vpm {

std::map<int, LabelVolume> label_mesh(TetMesh& mesh, const Image& atlas) {
  const int m = mesh.num_tets(), n = mesh.num_vertices();
  FieldValues cell(m, 1), point(n, 1);
  const Eigen::Matrix3d inv = atlas.affine.topLeftCorner<3, 3>().inverse();
  const Eigen::Vector3d off = atlas.affine.topRightCorner<3, 1>();
  const Eigen::VectorXd vol = tet_volumes(mesh.vertices, mesh.tets);
  std::vector<int> lab(m);
  std::map<int, std::pair<int, double>> stats;
  for (int t = 0; t < m; ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += mesh.vertices.row(mesh.tets(t, k)).transpose();
    const Eigen::Vector3d v = inv * (c / 4 - off);
    const int i = int(std::lround(v.x())), j = int(std::lround(v.y())), k = int(std::lround(v.z()));
    int l = 0;
    if (i >= 0 && j >= 0 && k >= 0 && i < atlas.dims[0] && j < atlas.dims[1] && k < atlas.dims[2])
      l = int(std::lround(atlas.at(i, j, k)));
    lab[t] = l;
    cell(t, 0) = l;
    auto& st = stats[l];
    st.first += 1;
    st.second += vol[t];
  }
  // Vertex label: the most frequent label of its tets (ties: the larger summed volume).
  const Incidence inc = vertex_tet_incidence(n, mesh.tets);
  std::vector<std::pair<int, std::pair<int, double>>> cnt;
  for (int v = 0; v < n; ++v) {
    cnt.clear();
    for (int e = inc.offset[v]; e < inc.offset[v + 1]; ++e) {
      const int t = inc.tet_of[e];
      auto it = std::find_if(cnt.begin(), cnt.end(), [&](auto& p) { return p.first == lab[t]; });
      if (it == cnt.end()) cnt.push_back({lab[t], {1, vol[t]}});
      else it->second.first += 1, it->second.second += vol[t];
    }
    int best = 0;
    std::pair<int, double> bs{-1, 0};
    for (auto& p : cnt)
      if (p.second.first > bs.first || (p.second.first == bs.first && p.second.second > bs.second))
        best = p.first, bs = p.second;
    point(v, 0) = best;
  }
  mesh.set_cell_field("label", cell, true);
  mesh.set_point_field("label", point, true);
  std::map<int, LabelVolume> out;
  for (auto& [l, st] : stats) out[l] = LabelVolume{double(st.first), st.second};
  return out;
}

namespace detail {

std::map<int, LabelVolume> label_report(TetMesh& mesh, const Image& atlas) {
  const std::map<int, LabelVolume> labels = label_mesh(mesh, atlas);
  // voxel counts per label inside the atlas, for comparison
  std::map<int, double> voxels;
  for (float v : atlas.data) voxels[int(std::lround(v))] += 1;
  const double avox = std::abs(atlas.affine.topLeftCorner<3, 3>().determinant());
  std::map<int, LabelVolume> out;
  for (auto& [l, n] : voxels) {
    if (l == 0) continue;
    const auto e = labels.find(l);
    LabelVolume& r = out[l];
    if (e != labels.end()) r = e->second;
    r.voxels = n;
    r.voxel_volume_mm3 = n * avox;
  }
  return out;
}

}  // namespace detail
}  // namespace vpm
