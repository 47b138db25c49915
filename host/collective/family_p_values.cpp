// Each focus's family-wise p-value from its calibration's null, the normals left out
// (vpm/calibration.hpp family_p_values).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "vpm/calibration.hpp"

namespace vpm {

void family_p_values(Comparison& c, const CalibratedRule& rule) {
  const auto p = [](std::ptrdiff_t above, size_t n) {
    return (1.0 + static_cast<double>(above)) / (1.0 + static_cast<double>(n));
  };
  const auto& null = rule.cluster_null;
  // a cluster's rank: the normals whose largest cluster is at least as large, or whose strongest
  // is at least as strong, whichever is fewer (the two statistics combined by their smaller rank)
  const auto rank = [&](double candidates, double peak) {
    const auto larger = std::count_if(null.begin(), null.end(), [&](const auto& m) { return m.first >= candidates; });
    const auto stronger = std::count_if(null.begin(), null.end(), [&](const auto& m) { return m.second >= peak; });
    return std::min(larger, stronger);
  };
  std::vector<std::ptrdiff_t> null_ranks;
  for (const auto& [largest, strongest] : null) null_ranks.push_back(rank(largest, strongest));
  for (FocusCluster& f : c.clusters)
    if (!rule.tfce_null.empty()) {
      f.p_family = p(std::count_if(rule.tfce_null.begin(), rule.tfce_null.end(), [&](double m) { return m >= f.peak_tfce; }),
                     rule.tfce_null.size());
    } else if (!null.empty()) {
      const auto r = rank(f.candidates, std::abs(f.peak_z));
      f.p_family = p(std::count_if(null_ranks.begin(), null_ranks.end(), [&](std::ptrdiff_t m) { return m <= r; }), null.size());
    }
}

}  // namespace vpm
