// Display elements coarser than the tables' (collective/view_coarsen.hpp).
#include "collective/view_coarsen.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace vpm::detail {

ElementDefinition display_definition(const ElementDefinition& compared, int max_level) {
  ElementDefinition d = compared;
  d.level = std::min(compared.level, max_level);
  if (d.layout == ElementLayout::graded) d.shells = graded_shells(d.level);
  return d;
}

ElementCoarsening::ElementCoarsening(const CanonicalElements& fine, const CanonicalElements& coarse) {
  if (fine.definition() == coarse.definition()) return;
  parent_.resize(static_cast<size_t>(fine.size()));
  children_.resize(static_cast<size_t>(coarse.size()));
  for (int e = 0; e < fine.size(); ++e) {
    parent_[static_cast<size_t>(e)] = coarse.element_of(fine.centre(e));
    if (parent_[static_cast<size_t>(e)] >= 0) children_[static_cast<size_t>(parent_[static_cast<size_t>(e)])].push_back(e);
  }
}

std::vector<float> ElementCoarsening::mean(const std::vector<float>& fine) const {
  if (identity() || fine.empty()) return fine;
  std::vector<float> out(children_.size(), std::numeric_limits<float>::quiet_NaN());
  for (size_t c = 0; c < children_.size(); ++c) {
    double sum = 0;
    int n = 0;
    for (int e : children_[c])
      if (std::isfinite(fine[static_cast<size_t>(e)])) sum += fine[static_cast<size_t>(e)], ++n;
    if (n > 0) out[c] = static_cast<float>(sum / n);
  }
  return out;
}

std::vector<float> ElementCoarsening::rms(const std::vector<float>& fine) const {
  if (identity() || fine.empty()) return fine;
  std::vector<float> squares(fine.size());
  for (size_t e = 0; e < fine.size(); ++e) squares[e] = fine[e] * fine[e];
  std::vector<float> out = mean(squares);
  for (float& x : out) x = std::sqrt(x);
  return out;
}

std::vector<int> ElementCoarsening::least(const std::vector<int>& fine) const {
  if (identity() || fine.empty()) return fine;
  std::vector<int> out(children_.size(), 0);
  for (size_t c = 0; c < children_.size(); ++c)
    if (!children_[c].empty()) {
      out[c] = fine[static_cast<size_t>(children_[c][0])];
      for (int e : children_[c]) out[c] = std::min(out[c], fine[static_cast<size_t>(e)]);
    }
  return out;
}

std::vector<std::int32_t> ElementCoarsening::most_frequent(const std::vector<std::int32_t>& fine) const {
  if (identity() || fine.empty()) return fine;
  std::vector<std::int32_t> out(children_.size(), 0);
  std::map<std::int32_t, int> votes;
  for (size_t c = 0; c < children_.size(); ++c) {
    votes.clear();
    for (int e : children_[c]) ++votes[fine[static_cast<size_t>(e)]];
    int best = 0;
    for (const auto& [id, n] : votes)  // ascending ids: 0 first, so a nonzero id must beat it or tie
      if (n > best || (n == best && out[c] == 0)) best = n, out[c] = id;
  }
  return out;
}

}  // namespace vpm::detail
