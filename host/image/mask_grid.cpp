// Byte and float grids of the image layer (see mask_grid.hpp).
#include "image/mask_grid.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace vpm::detail {

const int kN6[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const int kN14[14][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},  {0, -1, 0},  {0, 0, 1},
                         {0, 0, -1}, {1, 1, 0},  {-1, -1, 0}, {1, 0, 1},  {-1, 0, -1},
                         {0, 1, 1},  {0, -1, -1}, {1, 1, 1},  {-1, -1, -1}};

namespace {

// Labels the connected components of voxels with value == `value` (comp id >= 0; others -1).
// Returns the component sizes.
template <int N>
std::vector<size_t> components(const Grid3& g, const std::vector<uint8_t>& v, uint8_t value,
                               const int (&nb)[N][3], std::vector<int>& comp) {
  comp.assign(g.size(), -1);
  std::vector<size_t> sizes;
  std::vector<size_t> stack;
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        const size_t s = g.idx(x, y, z);
        if (v[s] != value || comp[s] >= 0) continue;
        const int id = int(sizes.size());
        size_t count = 0;
        comp[s] = id;
        stack.push_back(s);
        while (!stack.empty()) {
          const size_t p = stack.back();
          stack.pop_back();
          ++count;
          const int px = int(p % g.nx), py = int((p / g.nx) % g.ny), pz = int(p / (size_t(g.nx) * g.ny));
          for (int k = 0; k < N; ++k) {
            const int qx = px + nb[k][0], qy = py + nb[k][1], qz = pz + nb[k][2];
            if (qx < 0 || qy < 0 || qz < 0 || qx >= g.nx || qy >= g.ny || qz >= g.nz) continue;
            const size_t q = g.idx(qx, qy, qz);
            if (v[q] == value && comp[q] < 0) {
              comp[q] = id;
              stack.push_back(q);
            }
          }
        }
        sizes.push_back(count);
      }
  return sizes;
}

// Keeps the largest foreground component and fills every background component that does

}  // namespace

template <int N>
std::pair<int, int> keep_largest_fill_cavities(const Grid3& g, std::vector<uint8_t>& m, const int (&nb)[N][3]) {
  std::vector<int> comp;
  auto sizes = components(g, m, 1, nb, comp);
  int removed = 0, filled = 0;
  if (sizes.size() > 1) {
    const int best = int(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
    for (size_t i = 0; i < m.size(); ++i)
      if (m[i] && comp[i] != best) m[i] = 0;
    removed = int(sizes.size()) - 1;
  }
  sizes = components(g, m, 0, nb, comp);
  std::vector<char> outside(sizes.size(), 0);
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        if (x != 0 && y != 0 && z != 0 && x != g.nx - 1 && y != g.ny - 1 && z != g.nz - 1) continue;
        const size_t s = g.idx(x, y, z);
        if (comp[s] >= 0) outside[comp[s]] = 1;
      }
  for (size_t c = 0; c < sizes.size(); ++c) filled += !outside[c];
  if (filled)
    for (size_t i = 0; i < m.size(); ++i)
      if (!m[i] && !outside[comp[i]]) m[i] = 1;
  return {removed, filled};
}

// Morphological dilation (value 1 grows) or erosion (value 0 grows) by a Euclidean ball of
// radius r cells, stamping only around boundary cells.
void morph(const Grid3& g, std::vector<uint8_t>& m, int r, bool dilate) {
  std::vector<std::array<int, 3>> ball;
  for (int z = -r; z <= r; ++z)
    for (int y = -r; y <= r; ++y)
      for (int x = -r; x <= r; ++x)
        if (x * x + y * y + z * z <= r * r) ball.push_back({x, y, z});
  const uint8_t grow = dilate ? 1 : 0;
  std::vector<uint8_t> out = m;
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        const size_t s = g.idx(x, y, z);
        if (m[s] != grow) continue;
        bool edge = false;
        for (int k = 0; k < 6 && !edge; ++k) {
          const int qx = x + kN6[k][0], qy = y + kN6[k][1], qz = z + kN6[k][2];
          if (qx < 0 || qy < 0 || qz < 0 || qx >= g.nx || qy >= g.ny || qz >= g.nz) continue;
          edge = m[g.idx(qx, qy, qz)] != grow;
        }
        if (!edge) continue;
        for (const auto& o : ball) {
          const int qx = x + o[0], qy = y + o[1], qz = z + o[2];
          if (qx < 0 || qy < 0 || qz < 0 || qx >= g.nx || qy >= g.ny || qz >= g.nz) continue;
          out[g.idx(qx, qy, qz)] = grow;
        }
      }
  m.swap(out);
}

template std::pair<int, int> keep_largest_fill_cavities<6>(const Grid3&, std::vector<uint8_t>&, const int (&)[6][3]);
template std::pair<int, int> keep_largest_fill_cavities<14>(const Grid3&, std::vector<uint8_t>&, const int (&)[14][3]);

void blur_axis(std::vector<float>& v, const Grid3& g, int axis, double sigma) {
  if (sigma <= 0) return;
  const int r = int(std::ceil(3 * sigma));
  std::vector<float> w(2 * r + 1);
  double sum = 0;
  for (int k = -r; k <= r; ++k) sum += w[k + r] = float(std::exp(-0.5 * k * k / (sigma * sigma)));
  for (auto& x : w) x = float(x / sum);
  const int n = axis == 0 ? g.nx : axis == 1 ? g.ny : g.nz;
  const size_t stride = axis == 0 ? 1 : axis == 1 ? size_t(g.nx) : size_t(g.nx) * g.ny;
  std::vector<float> line(n), out(n);
  const int na = axis == 0 ? g.ny : g.nx, nb = axis == 2 ? g.ny : g.nz;
  for (int b = 0; b < nb; ++b)
    for (int a = 0; a < na; ++a) {
      size_t base;
      if (axis == 0) base = g.idx(0, a, b);
      else if (axis == 1) base = g.idx(a, 0, b);
      else base = g.idx(a, b, 0);
      bool any = false;
      for (int i = 0; i < n; ++i) {
        line[i] = v[base + i * stride];
        any |= line[i] != 0;
      }
      if (!any) continue;
      for (int i = 0; i < n; ++i) {
        double acc = 0;
        const int lo = std::max(-r, -i), hi = std::min(r, n - 1 - i);
        for (int k = lo; k <= hi; ++k) acc += w[k + r] * line[i + k];
        out[i] = float(acc);
      }
      for (int i = 0; i < n; ++i) v[base + i * stride] = out[i];
    }
}

}  // namespace vpm::detail
