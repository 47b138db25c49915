// Point location in a tet mesh (mesh/tet_grid.hpp): the background built here, the walk itself
// in kernels/tet_locate.clh (included by mesh/tet_grid.hpp), compiled here and in the kernels.
#include "mesh/tet_grid.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "core/group_by_key.hpp"
#include "core/parallel.hpp"
#include "mesh/face_table.hpp"
#include "mesh/tet_geometry.hpp"

namespace vpm::detail {

std::vector<int> tet_neighbors(const Tets& tets, Triangles* boundary) {
  std::vector<int> nbr(4 * static_cast<size_t>(tets.rows()), -1);
  const FaceTable ft = face_table(tets);
  if (boundary) *boundary = boundary_faces(ft, tets);
  ft.for_each_group([&](int first, int count) {
    if (count != 2) return;  // boundary, or non-manifold (no single neighbour)
    const int a = ft.entries[static_cast<size_t>(first)].slot, b = ft.entries[static_cast<size_t>(first) + 1].slot;
    nbr[static_cast<size_t>(a)] = b / 4;
    nbr[static_cast<size_t>(b)] = a / 4;
  });
  return nbr;
}

namespace {

// The uniform grid of f over the positions x: about one cell per tet over the bounding box
// (cells capped at 128 a side); each tet is listed in every cell its bounding box (grown by a
// quarter cell) overlaps.
void bin_tets(TetGrid& f, const Points& x, const Tets& tets) {
  Eigen::RowVector3d lo = x.colwise().minCoeff(), hi = x.colwise().maxCoeff();
  const Eigen::RowVector3d ext = (hi - lo).cwiseMax(1e-300);
  double h = std::cbrt(ext.prod() / std::max(1, f.m));
  for (int c = 0; c < 3; ++c) h = std::max(h, ext(c) / 128.0);
  lo.array() -= 0.5 * h;
  for (int c = 0; c < 3; ++c) {
    f.lo[c] = lo(c);
    f.dims[c] = std::max(1, static_cast<int>(std::ceil((ext(c) + h) / h)));
  }
  f.inv_h = 1.0 / h;
  const int gx = f.dims[0], gy = f.dims[1], gz = f.dims[2];
  const size_t cells = static_cast<size_t>(gx) * gy * gz;
  auto cell_range = [&](int t, int* a, int* b) {
    for (int c = 0; c < 3; ++c) {
      double mn = 1e300, mx = -1e300;
      for (int k = 0; k < 4; ++k) {
        mn = std::min(mn, x(tets(t, k), c));
        mx = std::max(mx, x(tets(t, k), c));
      }
      a[c] = std::clamp(static_cast<int>(std::floor((mn - 0.25 * h - f.lo[c]) * f.inv_h)), 0, f.dims[c] - 1);
      b[c] = std::clamp(static_cast<int>(std::floor((mx + 0.25 * h - f.lo[c]) * f.inv_h)), 0, f.dims[c] - 1);
    }
  };
  // the (cell, tet) pairs grouped by cell, each cell's tets in ascending order
  group_by_key(
      f.m, cells,
      [&](int t, auto&& visit) {
        int a[3], b[3];
        cell_range(t, a, b);
        for (int k = a[2]; k <= b[2]; ++k)
          for (int j = a[1]; j <= b[1]; ++j)
            for (int i = a[0]; i <= b[0]; ++i) visit(i + gx * (j + static_cast<size_t>(gy) * k));
      },
      f.cell_start, f.cell_tets);
}

}  // namespace

void build_grid(TetGrid& f, const Points& x, const Tets& tets, const std::vector<int>& nbr) {
  f.n = static_cast<int>(x.rows());
  f.m = static_cast<int>(tets.rows());
  f.tets = &tets;
  f.nbr = &nbr;
  f.inv.clear();
  bin_tets(f, x, tets);
}

void build_background(TetGrid& f, const Points& x, const Tets& tets, const std::vector<int>& nbr) {
  build_grid(f, x, tets, nbr);
  f.inv.resize(12 * static_cast<size_t>(f.m));  // every entry written below, by the thread that owns it
  parallel_for(f.m, 8192, [&](int t0, int t1) {
    for (int t = t0; t < t1; ++t) {
      double e[3][3];
      tet_edges(x, tets, t, e);
      double* q = &f.inv[12 * static_cast<size_t>(t)];
      for (int c = 0; c < 3; ++c) q[c] = x(tets(t, 0), c);
      tg_inverse_rows(e[0], e[1], e[2], q + 3);
    }
  });
}


void bary(const TetGrid& f, int t, const Eigen::Vector3d& p, double* l) {
  tl_bary(f.inv.data(), t, p.x(), p.y(), p.z(), l);
}

TlGrid tl_grid(const TetGrid& f) {
  TlGrid g;
  for (int c = 0; c < 3; ++c) {
    g.lo[c] = f.lo[c];
    g.dims[c] = f.dims[c];
  }
  g.inv_h = f.inv_h;
  g.cell_start = f.cell_start.data();
  g.cell_tets = f.cell_tets.data();
  return g;
}

int start_tet(const TetGrid& f, const Eigen::Vector3d& p) {
  const TlGrid g = tl_grid(f);
  return tl_start(&g, p.x(), p.y(), p.z());
}

int locate(const TetGrid& f, const Eigen::Vector3d& p, int t, double* l, long long* st) {
  const TlGrid g = tl_grid(f);
  return tl_locate(p.x(), p.y(), p.z(), t, f.inv.data(), f.nbr->data(), &g, l, st);
}

}  // namespace vpm::detail
