#pragma once
// Private: the arrays the sample generator reads (kernels/element_samples.clh, compiled here and
// in kernels/sampling.cl), held by a CanonicalElements (CanonicalElements::arrays()): the
// layout, the R3 points and radii, and, made on first use, the directions table and samples().
#include <cmath>
#include <mutex>
#include <vector>

#include "vpm/elements.hpp"

namespace vpm::detail {

#include "kernels/element_samples.clh"

struct ElementArrays {
  int samples = 0;            ///< S
  std::vector<int> offset;    ///< K + 1: the first element of each shell, then the element count
  std::vector<int> level;     ///< K: the triangle level of each shell
  std::vector<int> first;     ///< per level 0..L: its first triangle in `corners`
  std::vector<double> corners;  ///< 9 per triangle of every level: corners a, b, c
  std::vector<double> u;        ///< S x 3: es_r3(i + 1) for sample i
  std::vector<double> radius;   ///< K x S: es_radius of sample i in shell k

  mutable std::once_flag directions_made;  ///< element_directions fills `directions` once
  mutable std::vector<double> directions;  ///< per triangle of every level, S x 3 (EsLayout::dir)
  mutable std::once_flag samples_made;     ///< CanonicalElements::samples() fills `points` once
  mutable Points points;
};

/// The directions table of `a`, made on the first call (on the host threads) and kept.
const std::vector<double>& element_directions(const ElementArrays& a);

/// The generator's view of `a` (pointers into its arrays; `dir` null until element_directions).
inline EsLayout es_layout(const ElementArrays& a) {
  EsLayout L;
  L.shells = static_cast<int>(a.level.size());
  L.samples = a.samples;
  L.offset = a.offset.data();
  L.level = a.level.data();
  L.first = a.first.data();
  L.corners = a.corners.data();
  L.u = a.u.data();
  L.radius = a.radius.data();
  L.dir = a.directions.empty() ? nullptr : a.directions.data();
  return L;
}

}  // namespace vpm::detail
