#pragma once
// Byte and float grids of the image layer: connected components, largest component and
// cavity filling, morphological closing, separable Gaussian smoothing.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace vpm::detail {

/// Dimensions of a 3-D grid stored x-fastest.
struct Grid3 {
  int nx = 0, ny = 0, nz = 0;
  size_t size() const { return size_t(nx) * ny * nz; }
  size_t idx(int x, int y, int z) const { return size_t(x) + size_t(nx) * (size_t(y) + size_t(ny) * z); }
};

/// Neighbour offsets: 6-connectivity, or the 14 edges of the Freudenthal (Kuhn) split used by
/// marching tetrahedra (axes, the three (+,+) face diagonals, the (+,+,+) diagonal, and negatives).
extern const int kN6[6][3];
extern const int kN14[14][3];

/// Keeps the largest foreground (value 1) component of `m` under the neighbourhood `nb` and
/// fills every background component that does not touch the grid border.
/// Returns {foreground components removed, cavities filled}.
template <int N>
std::pair<int, int> keep_largest_fill_cavities(const Grid3& g, std::vector<uint8_t>& m, const int (&nb)[N][3]);

/// Morphological dilation (value 1 grows) or erosion (value 0 grows) by a Euclidean ball of
/// radius r cells, stamping only around boundary cells.
void morph(const Grid3& g, std::vector<uint8_t>& m, int r, bool dilate);

/// Gaussian blur of `v` along one axis (0, 1, 2), sigma in cells; lines that are all zero are
/// skipped; the kernel is truncated at 3 sigma and at the grid ends.
void blur_axis(std::vector<float>& v, const Grid3& g, int axis, double sigma);

}  // namespace vpm::detail
