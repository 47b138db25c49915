#include "vpm/mesh_order.hpp"

#include <algorithm>
#include <cstdint>
#include <numeric>

namespace vpm {

namespace {

// Spreads the low 21 bits of v so that there are two zero bits between consecutive ones.
uint64_t spread3(uint64_t v) {
  v &= 0x1fffff;
  v = (v | v << 32) & 0x1f00000000ffffULL;
  v = (v | v << 16) & 0x1f0000ff0000ffULL;
  v = (v | v << 8) & 0x100f00f00f00f00fULL;
  v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
  v = (v | v << 2) & 0x1249249249249249ULL;
  return v;
}

// Z-order codes of the rows of p over the box [lo, lo + extent]^3.
std::vector<uint64_t> morton_codes(const Points& p, const Eigen::RowVector3d& lo, double extent) {
  const double scale = extent > 0 ? double((1 << 21) - 1) / extent : 0.0;
  std::vector<uint64_t> code(static_cast<size_t>(p.rows()));
  for (Eigen::Index i = 0; i < p.rows(); ++i) {
    uint64_t c = 0;
    for (int a = 0; a < 3; ++a) {
      const double q = std::clamp((p(i, a) - lo(a)) * scale, 0.0, double((1 << 21) - 1));
      c |= spread3(static_cast<uint64_t>(q)) << a;
    }
    code[static_cast<size_t>(i)] = c;
  }
  return code;
}

std::vector<int> order_by(const std::vector<uint64_t>& code) {
  std::vector<int> order(code.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return code[a] < code[b]; });
  return order;
}

// Rows of `values` in the order `old_of_new`.
FieldValues permuted(const FieldValues& values, const std::vector<int>& old_of_new) {
  FieldValues out(values.rows(), values.cols());
  for (size_t i = 0; i < old_of_new.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = values.row(old_of_new[i]);
  return out;
}

}  // namespace

std::vector<int> spatial_order(const Points& points) {
  if (points.rows() == 0) return {};
  const Eigen::RowVector3d lo = points.colwise().minCoeff();
  return order_by(morton_codes(points, lo, (points.colwise().maxCoeff() - lo).maxCoeff()));
}

std::vector<int> sort_spatially(TetMesh& mesh) {
  const int n = mesh.num_vertices(), m = mesh.num_tets();
  if (n == 0) return {};
  const Eigen::RowVector3d lo = mesh.vertices.colwise().minCoeff();
  const double extent = (mesh.vertices.colwise().maxCoeff() - lo).maxCoeff();
  const std::vector<int> vertex_order = order_by(morton_codes(mesh.vertices, lo, extent));
  std::vector<int> new_of_old(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) new_of_old[static_cast<size_t>(vertex_order[static_cast<size_t>(i)])] = i;
  Points centroids(m, 3);
  for (int t = 0; t < m; ++t) {
    Eigen::RowVector3d c = Eigen::RowVector3d::Zero();
    for (int k = 0; k < 4; ++k) c += mesh.vertices.row(mesh.tets(t, k));
    centroids.row(t) = 0.25 * c;
  }
  const std::vector<int> tet_order = order_by(morton_codes(centroids, lo, extent));

  Points vertices(n, 3);
  for (int i = 0; i < n; ++i) vertices.row(i) = mesh.vertices.row(vertex_order[static_cast<size_t>(i)]);
  Tets tets(m, 4);
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) tets(t, k) = new_of_old[static_cast<size_t>(mesh.tets(tet_order[static_cast<size_t>(t)], k))];
  mesh.vertices = std::move(vertices);
  mesh.tets = std::move(tets);
  for (Field& f : mesh.point_data) f.values = permuted(f.values, vertex_order);
  for (Field& f : mesh.cell_data) f.values = permuted(f.values, tet_order);
  return vertex_order;
}

}  // namespace vpm
