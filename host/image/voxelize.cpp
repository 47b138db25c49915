// A closed surface rasterised by winding numbers along grid columns (vpm/voxelize.hpp).
#include "vpm/voxelize.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"

namespace vpm {

Image voxelize_surface(const TriSurface& s, double voxel_mm, int pad_voxels) {
  if (!(voxel_mm > 0)) throw InputError("voxelize: voxel size " + format_sig(voxel_mm) + " must be > 0");
  if (s.triangles.rows() == 0 || s.vertices.rows() == 0) throw InputError("voxelize: the surface is empty");
  const Eigen::RowVector3d lo = s.vertices.colwise().minCoeff(), hi = s.vertices.colwise().maxCoeff();
  Image img;
  double count = 1;
  for (int a = 0; a < 3; ++a) {
    img.dims[static_cast<size_t>(a)] = static_cast<int>(std::ceil((hi(a) - lo(a)) / voxel_mm)) + 1 + 2 * pad_voxels;
    img.spacing[static_cast<size_t>(a)] = voxel_mm;
    count *= img.dims[static_cast<size_t>(a)];
  }
  if (count > 512.0 * 512.0 * 512.0)
    throw InputError("voxelize: " + std::to_string(img.dims[0]) + " x " + std::to_string(img.dims[1]) + " x " +
                     std::to_string(img.dims[2]) + " voxels of " + format_sig(voxel_mm) +
                     " is more than 512^3: choose larger voxels");
  img.affine = Eigen::Matrix4d::Identity();
  img.affine.topLeftCorner<3, 3>() *= voxel_mm;
  for (int a = 0; a < 3; ++a) img.affine(a, 3) = lo(a) - pad_voxels * voxel_mm;
  img.affine_source = "sform";
  img.data.assign(img.size(), 0.0f);
  const int nx = img.dims[0], ny = img.dims[1], nz = img.dims[2];
  // Column (i, j) is the line x = x0 + i h + dx, y = y0 + j h + dy along z; the tiny offsets keep
  // it off the surface's vertices and edges (a crossing there would count twice or not at all).
  const double dx = 1.234567e-7 * voxel_mm, dy = 2.345678e-7 * voxel_mm;
  const double x0 = img.affine(0, 3) + dx, y0 = img.affine(1, 3) + dy;
  std::vector<std::vector<std::pair<double, int>>> crossings(static_cast<size_t>(nx) * ny);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t) {
    const Eigen::Vector3d a = s.vertices.row(s.triangles(t, 0)), b = s.vertices.row(s.triangles(t, 1)),
                          c = s.vertices.row(s.triangles(t, 2));
    const double area2 = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());  // 2 x signed xy area
    if (area2 == 0) continue;  // parallel to the columns: no crossing
    const int i0 = std::max(0, static_cast<int>(std::ceil((std::min({a.x(), b.x(), c.x()}) - x0) / voxel_mm)));
    const int i1 = std::min(nx - 1, static_cast<int>(std::floor((std::max({a.x(), b.x(), c.x()}) - x0) / voxel_mm)));
    const int j0 = std::max(0, static_cast<int>(std::ceil((std::min({a.y(), b.y(), c.y()}) - y0) / voxel_mm)));
    const int j1 = std::min(ny - 1, static_cast<int>(std::floor((std::max({a.y(), b.y(), c.y()}) - y0) / voxel_mm)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double px = x0 + i * voxel_mm, py = y0 + j * voxel_mm;
        // barycentric coordinates of (px, py) in the xy projection
        const double wa = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area2;
        const double wb = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area2;
        const double wc = 1 - wa - wb;
        if (wa < 0 || wb < 0 || wc < 0) continue;
        const double z = wa * a.z() + wb * b.z() + wc * c.z();
        crossings[static_cast<size_t>(i) + static_cast<size_t>(nx) * j].push_back({z, area2 > 0 ? 1 : -1});
      }
  }
  const double z0 = img.affine(2, 3) + 3.456789e-7 * voxel_mm;  // off the surface, as the columns
  detail::parallel_for(ny, 8, [&](int j0, int j1) {
    for (int j = j0; j < j1; ++j)
      for (int i = 0; i < nx; ++i) {
        auto& col = crossings[static_cast<size_t>(i) + static_cast<size_t>(nx) * j];
        std::sort(col.begin(), col.end());
        int winding = 0;
        size_t next = 0;
        for (int k = 0; k < nz; ++k) {
          const double z = z0 + k * voxel_mm;
          while (next < col.size() && col[next].first < z) winding += col[next++].second;
          if (winding != 0) img.data[img.index(i, j, k)] = 1.0f;
        }
      }
  });
  return img;
}

}  // namespace vpm
