#include "vpm/map_back.hpp"

#include <cmath>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/locate.hpp"

namespace vpm {

TetMesh native_mesh_with_values(const TetMesh& registered, const CanonicalElements& el,
                                const std::vector<std::vector<double>>& values, const std::vector<std::string>& names) {
  TetMesh out;
  out.vertices = native_positions(registered, "map back: the registered mesh");
  out.tets = registered.tets;
  out.point_data = registered.point_data;
  out.cell_data = registered.cell_data;
  std::vector<int> vertex_element(out.num_vertices()), tet_element(out.num_tets());
  for (int v = 0; v < out.num_vertices(); ++v) vertex_element[v] = el.element_of(registered.vertices.row(v).transpose());
  for (int t = 0; t < out.num_tets(); ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += 0.25 * registered.vertices.row(registered.tets(t, k)).transpose();
    tet_element[t] = el.element_of(c);
  }
  for (size_t i = 0; i < values.size(); ++i) {
    FieldValues pv(out.num_vertices(), 1), cv(out.num_tets(), 1);
    for (int v = 0; v < out.num_vertices(); ++v) pv(v, 0) = vertex_element[v] >= 0 ? values[i][vertex_element[v]] : NAN;
    for (int t = 0; t < out.num_tets(); ++t) cv(t, 0) = tet_element[t] >= 0 ? values[i][tet_element[t]] : NAN;
    out.set_point_field(names[i], pv);
    out.set_cell_field(names[i], cv);
  }
  return out;
}

Image native_volume(const TetMesh& registered, const CanonicalElements& el, const std::vector<double>& values,
                    const Image& grid, float outside) {
  const Points native = native_positions(registered, "map back: the registered mesh");
  const TetLocator locator(native, registered.tets);
  Image out = grid;
  out.data.assign(grid.size(), outside);
  const int nk = grid.dims[2];
  detail::parallel_for(nk, 1, [&](int k0, int k1) {
    for (int k = k0; k < k1; ++k) {
      int hint = -1;
      for (int j = 0; j < grid.dims[1]; ++j)
        for (int i = 0; i < grid.dims[0]; ++i) {
          const Location l = locator.locate(grid.to_world(Eigen::Vector3d(i, j, k)), hint);
          hint = l.tet;
          if (!l.inside()) continue;
          Eigen::Vector3d b = Eigen::Vector3d::Zero();
          for (int c = 0; c < 4; ++c) b += l.bary[c] * registered.vertices.row(registered.tets(l.tet, c)).transpose();
          const int e = el.element_of(b);
          if (e >= 0 && !std::isnan(values[e])) out.data[grid.index(i, j, k)] = static_cast<float>(values[e]);
        }
    }
  });
  return out;
}

}  // namespace vpm
