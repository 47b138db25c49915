// Simplification of a closed triangulated surface by half-edge collapses
// (map/surface_collapse.hpp).
#include "map/surface_collapse.hpp"

#include <limits>
#include <string>

#include "vpm/error.hpp"

namespace vpm::detail {

// Half-edge collapses in passes over an independent set (no two collapses of a pass touch the
// same ring) until 4 vertices are left, lightest first: each vertex carries the input area of
// the vertices collapsed into it (`weight`), and a vertex goes into its lightest neighbour, so
// the clusters grow evenly and every level's triangles can be both well shaped and of their
// share of the area. Returns the passes run.
int simplify(CollapsibleSurface& s, const Points& in, std::vector<double> weight) {
  const int n = static_cast<int>(in.rows());
  std::vector<char> touched(static_cast<size_t>(n));
  std::vector<int> order;
  int pass = 0;
  while (s.alive_count > 4) {
    order.clear();
    for (int u = 0; u < n; ++u)
      if (s.alive[static_cast<size_t>(u)]) order.push_back(u);
    std::stable_sort(order.begin(), order.end(),
                     [&](int a, int b) { return weight[static_cast<size_t>(a)] < weight[static_cast<size_t>(b)]; });
    int done = 0;
    for (int attempt = 0; attempt < 2 && done == 0; ++attempt) {
      const size_t degree_cap = attempt == 0 ? 12 : std::numeric_limits<size_t>::max();
      std::fill(touched.begin(), touched.end(), 0);
      for (int u : order) {
        if (s.alive_count <= 4) break;
        if (touched[static_cast<size_t>(u)]) continue;
        const std::vector<int> nu = s.neighbours(u);
        std::vector<int> candidates = nu;
        std::sort(candidates.begin(), candidates.end(), [&](int a, int b) {
          const double wa = weight[static_cast<size_t>(a)], wb = weight[static_cast<size_t>(b)];
          if (wa != wb) return wa < wb;
          return (in.row(a) - in.row(u)).squaredNorm() < (in.row(b) - in.row(u)).squaredNorm();
        });
        for (int v : candidates) {
          if (touched[static_cast<size_t>(v)] && attempt == 0) continue;
          if (nu.size() + s.neighbours(v).size() - 4 > degree_cap) continue;
          if (!s.collapsible(u, v, nu)) continue;
          s.collapse(u, v, pass);
          weight[static_cast<size_t>(v)] += weight[static_cast<size_t>(u)];
          touched[static_cast<size_t>(u)] = touched[static_cast<size_t>(v)] = 1;
          for (int w : nu) touched[static_cast<size_t>(w)] = 1;
          ++done;
          break;
        }
      }
    }
    if (done == 0)
      throw NumericalError("sphere map: the boundary surface could not be simplified below " +
                           std::to_string(s.alive_count) + " vertices (is it a closed genus-0 surface?)");
    ++pass;
  }
  return pass;
}

}  // namespace vpm::detail
