#pragma once
// Private: the page of a cohort whose element tables are finer than it draws (vpm/cohort_view.hpp,
// CohortViewOptions::max_display_level; docs/view.md "Tables finer than the page"). Every per-element array
// is carried to coarser display elements: each fine element belongs to the display element that
// holds its centre.
#include <cstdint>
#include <vector>

#include "vpm/elements.hpp"

namespace vpm::detail {

/// The display definition of tables of `compared`: the same layout and samples at
/// min(level, max_level) (graded: its shells; shells: the same shells).
ElementDefinition display_definition(const ElementDefinition& compared, int max_level);

class ElementCoarsening {
 public:
  /// Identity when both are the same definition.
  ElementCoarsening(const CanonicalElements& fine, const CanonicalElements& coarse);
  bool identity() const { return parent_.empty(); }
  /// The display element of fine element e (e itself for the identity; -1 past the ball).
  int of(int e) const { return identity() ? e : parent_[static_cast<size_t>(e)]; }
  /// Per display element: the mean over its fine elements of their finite values (NaN: none).
  std::vector<float> mean(const std::vector<float>& fine) const;
  /// Per display element: the root mean square of its fine elements' finite values (spreads).
  std::vector<float> rms(const std::vector<float>& fine) const;
  /// Per display element: the least of its fine elements' values (counts; 0 without any).
  std::vector<int> least(const std::vector<int>& fine) const;
  /// Per display element: the most frequent of its fine elements' values (focus ids, 0 = none);
  /// a tie goes to the smaller nonzero id, so a focus half of a display element keeps it.
  std::vector<std::int32_t> most_frequent(const std::vector<std::int32_t>& fine) const;

 private:
  std::vector<int> parent_;  // per fine element
  std::vector<std::vector<int>> children_;  // per display element
};

}  // namespace vpm::detail
