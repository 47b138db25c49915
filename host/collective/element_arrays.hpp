#pragma once
// Private: the arrays the sample generator reads (kernels/element_samples.clh, compiled here and
// in kernels/sampling.cl), held by a CanonicalElements (CanonicalElements::arrays()), and the
// samples() it makes from them on first use.
#include <cmath>
#include <mutex>
#include <vector>

#include "vpm/elements.hpp"

namespace vpm::detail {

#include "kernels/element_samples.clh"

struct ElementArrays {
  int samples = 0;            ///< S
  std::vector<int> offset;    ///< K + 1: the first element of each shell, then the element count
  std::vector<double> radius3;  ///< K + 1: r_k^3, the last 1
  std::vector<int> level;     ///< K: the triangle level of each shell
  std::vector<int> first;     ///< per level 0..L: its first triangle in `corners`
  std::vector<double> corners;  ///< 9 per triangle of every level: corners a, b, c

  std::once_flag samples_made;  ///< CanonicalElements::samples() fills `points` once
  Points points;
};

/// The generator's view of `a` (pointers into its arrays).
inline EsLayout es_layout(const ElementArrays& a) {
  EsLayout L;
  L.shells = static_cast<int>(a.level.size());
  L.samples = a.samples;
  L.offset = a.offset.data();
  L.radius3 = a.radius3.data();
  L.level = a.level.data();
  L.first = a.first.data();
  L.corners = a.corners.data();
  return L;
}

}  // namespace vpm::detail
