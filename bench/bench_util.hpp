#pragma once
// Small helpers the benchmark programs share.
#include <algorithm>
#include <string>
#include <vector>

namespace vpm::bench {

/// The median (mean of the middle two for an even count); 0 for none.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// "100000,400000" -> {100000, 400000}; empty items are skipped ("" = none).
inline std::vector<long> parse_sizes(const std::string& s) {
  std::vector<long> out;
  size_t p = 0;
  while (p <= s.size()) {
    const size_t q = std::min(s.find(',', p), s.size());
    if (q > p) out.push_back(std::stol(s.substr(p, q - p)));
    p = q + 1;
  }
  return out;
}

}  // namespace vpm::bench
