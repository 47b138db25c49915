// Point location in a tet mesh (mesh/tet_grid.hpp); the OpenCL twin is in kernels/moser.cl.
#include "mesh/tet_grid.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "core/group_by_key.hpp"
#include "core/parallel.hpp"
#include "mesh/face_table.hpp"

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
      const Eigen::Vector3d a = x.row(tets(t, 0)).transpose();
      Eigen::Matrix3d M;
      for (int c = 0; c < 3; ++c) M.col(c) = x.row(tets(t, c + 1)).transpose() - a;
      const Eigen::Matrix3d Mi = M.inverse();
      double* q = &f.inv[12 * static_cast<size_t>(t)];
      q[0] = a.x();
      q[1] = a.y();
      q[2] = a.z();
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) q[3 + 3 * r + c] = Mi(r, c);
    }
  });
}


namespace {
constexpr int kMaxWalk = 64;
constexpr double kInsideEps = -1e-12;
constexpr double kOutsideClamp = -0.05;
}  // namespace

void bary(const TetGrid& f, int t, const Eigen::Vector3d& p, double* l) {
  const double* q = &f.inv[12 * static_cast<size_t>(t)];
  const double dx = p.x() - q[0], dy = p.y() - q[1], dz = p.z() - q[2];
  l[1] = q[3] * dx + q[4] * dy + q[5] * dz;
  l[2] = q[6] * dx + q[7] * dy + q[8] * dz;
  l[3] = q[9] * dx + q[10] * dy + q[11] * dz;
  l[0] = 1.0 - l[1] - l[2] - l[3];
}

namespace {
inline double min4(const double* l) { return std::min(std::min(l[0], l[1]), std::min(l[2], l[3])); }

inline void clamp_bary(double* l) {
  double s = 0;
  for (int k = 0; k < 4; ++k) {
    l[k] = std::max(l[k], 0.0);
    s += l[k];
  }
  for (int k = 0; k < 4; ++k) l[k] = s <= 0 ? 0.25 : l[k] / s;
}

}  // namespace

int locate(const TetGrid& f, const Eigen::Vector3d& p, int t, double* l, long long* st) {
  const std::vector<int>& nbr = *f.nbr;
  for (int s = 0; s < kMaxWalk; ++s) {
    bary(f, t, p, l);
    int k = 0;
    for (int c = 1; c < 4; ++c)
      if (l[c] < l[k]) k = c;
    if (l[k] >= kInsideEps) return t;
    const int nb = nbr[4 * static_cast<size_t>(t) + k];
    if (nb < 0) {
      if (l[k] > kOutsideClamp) {
        clamp_bary(l);
        st[2] += 1;
        return t;
      }
      break;
    }
    t = nb;
    st[0] += 1;
  }
  st[1] += 1;
  int idx[3];
  for (int c = 0; c < 3; ++c)
    idx[c] = std::clamp(static_cast<int>(std::floor((p(c) - f.lo[c]) * f.inv_h)), 0, f.dims[c] - 1);
  const size_t cell = idx[0] + f.dims[0] * (idx[1] + static_cast<size_t>(f.dims[1]) * idx[2]);
  int best = -1;
  double best_score = -1e300, lb[4];
  for (int j = f.cell_start[cell]; j < f.cell_start[cell + 1]; ++j) {
    const int c = f.cell_tets[j];
    bary(f, c, p, lb);
    const double sc = min4(lb);
    if (sc > best_score) {
      best_score = sc;
      best = c;
    }
  }
  if (best < 0) best = t;
  bary(f, best, p, l);
  if (min4(l) < kInsideEps) {
    clamp_bary(l);
    st[2] += 1;
  }
  return best;
}

}  // namespace vpm::detail
