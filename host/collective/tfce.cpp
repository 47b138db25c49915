// Threshold-free cluster enhancement on the elements' adjacency (vpm/tfce.hpp): the heights are
// swept from the top down with a union-find of the elements reached so far; between two heights
// at which elements enter, the components stay the same, so each such span costs one pass over
// the elements already in, whatever its number of steps.
#include "vpm/tfce.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "vpm/error.hpp"

namespace vpm {

namespace {

// Union by size without path compression (depth O(log n)), each node holding a value such that
// an element's score is the sum of the values on its path to its root: adding to a whole
// component is one addition at its root, and a root joined under another subtracts the other's
// value so that its members keep their sums.
struct Components {
  std::vector<int> parent, size;
  std::vector<double> value;
  explicit Components(size_t n) : parent(n), size(n, 1), value(n, 0.0) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int a) const {
    while (parent[static_cast<size_t>(a)] != a) a = parent[static_cast<size_t>(a)];
    return a;
  }
  void join(int a, int b) {
    a = find(a), b = find(b);
    if (a == b) return;
    if (size[static_cast<size_t>(a)] < size[static_cast<size_t>(b)]) std::swap(a, b);
    parent[static_cast<size_t>(b)] = a;
    value[static_cast<size_t>(b)] -= value[static_cast<size_t>(a)];
    size[static_cast<size_t>(a)] += size[static_cast<size_t>(b)];
  }
  double sum_to_root(int a) const {
    double v = value[static_cast<size_t>(a)];
    while (parent[static_cast<size_t>(a)] != a) {
      a = parent[static_cast<size_t>(a)];
      v += value[static_cast<size_t>(a)];
    }
    return v;
  }
};

}  // namespace

std::vector<double> tfce_scores(const CanonicalElements& el, const std::vector<double>& z, int sign,
                                const TfceParameters& p) {
  const size_t n = static_cast<size_t>(el.size());
  if (z.size() != n)
    throw InputError("tfce: " + std::to_string(z.size()) + " values for " + std::to_string(n) + " elements");
  if (sign != 1 && sign != -1) throw InputError("tfce: the sign must be +1 or -1");
  if (!(p.step > 0 && p.extent_power >= 0 && p.height_power >= 0 && std::isfinite(p.extent_power) &&
        std::isfinite(p.height_power)))
    throw InputError("tfce: the step must be positive and the powers finite and >= 0");
  std::vector<double> score(n, 0.0);
  std::vector<int> order;  // the elements at or above the first height, highest first
  double top = 0;
  for (size_t e = 0; e < n; ++e) {
    const double v = sign * z[e];
    if (std::isnan(v) || v < p.step) continue;
    order.push_back(static_cast<int>(e));
    top = std::max(top, v);
  }
  if (order.empty()) return score;
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const double va = sign * z[static_cast<size_t>(a)], vb = sign * z[static_cast<size_t>(b)];
    return va != vb ? va > vb : a < b;
  });
  // an infinite z (a reference without spread) would sweep forever: its heights stop at the
  // highest finite value's, where the element counts as reaching every height
  double finite_top = 0;
  for (int e : order)
    if (std::isfinite(z[static_cast<size_t>(e)])) finite_top = std::max(finite_top, sign * z[static_cast<size_t>(e)]);
  if (!std::isfinite(top)) top = std::max(finite_top, p.step);
  const long levels = static_cast<long>(std::floor(top / p.step + 1e-9));
  // sum over k = lo .. hi of (k step)^H step: closed for the paper's H = 2, else term by term
  const auto weight = [&](long lo, long hi) {
    if (p.height_power == 2.0) {
      const auto sq = [](double k) { return k * (k + 1) * (2 * k + 1) / 6.0; };
      return (sq(static_cast<double>(hi)) - sq(static_cast<double>(lo - 1))) * p.step * p.step * p.step;
    }
    double w = 0;
    for (long k = lo; k <= hi; ++k) w += std::pow(static_cast<double>(k) * p.step, p.height_power) * p.step;
    return w;
  };
  if (p.height_power != 2.0 && levels > 100'000'000L)
    throw InputError("tfce: |z| up to " + std::to_string(top) + " needs too many steps of " + std::to_string(p.step));
  Components comp(n);
  std::vector<char> in(n, 0);
  std::vector<int> roots;  // the components' roots (some stale: joined under another since)
  const CanonicalElements::Adjacency& adj = el.adjacency();
  // the level index an element enters at: the highest k with k step <= sign z (all for infinite z)
  const auto level_of = [&](int e) {
    const double v = sign * z[static_cast<size_t>(e)];
    return std::isfinite(v) ? std::min(levels, static_cast<long>(std::floor(v / p.step + 1e-9))) : levels;
  };
  const auto extent = [&](int size) {
    return p.extent_power == 0.5 ? std::sqrt(static_cast<double>(size)) : std::pow(static_cast<double>(size), p.extent_power);
  };
  size_t added = 0;
  long k = levels;
  while (k >= 1) {
    while (added < order.size() && level_of(order[added]) >= k) {
      const int e = order[added++];
      in[static_cast<size_t>(e)] = 1;
      roots.push_back(e);
      for (int nb : adj.of(e))
        if (in[static_cast<size_t>(nb)]) comp.join(e, nb);
    }
    // nothing enters until the next element's level: the components stay as they are down to it
    const long next = added < order.size() ? level_of(order[added]) : 0;
    const double w = weight(next + 1, k);
    size_t live = 0;
    for (int r : roots)
      if (comp.parent[static_cast<size_t>(r)] == r) {
        comp.value[static_cast<size_t>(r)] += extent(comp.size[static_cast<size_t>(r)]) * w;
        roots[live++] = r;
      }
    roots.resize(live);
    k = next;
  }
  for (size_t i = 0; i < added; ++i) score[static_cast<size_t>(order[i])] = comp.sum_to_root(order[i]);
  return score;
}

}  // namespace vpm
