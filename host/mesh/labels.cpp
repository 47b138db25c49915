// Labels read at points of a tet mesh and their Dice overlap (vpm/labels.hpp).
#include "vpm/labels.hpp"

#include <string>
#include <unordered_map>

#include "vpm/error.hpp"
#include "vpm/locate.hpp"

namespace vpm {

std::vector<int> sample_labels(const Points& vertices, const Tets& tets, const std::vector<int>& tet_labels,
                               const Points& points, int outside_label, double outside_tolerance) {
  if (static_cast<long>(tet_labels.size()) != tets.rows())
    throw InputError("sample_labels: " + std::to_string(tet_labels.size()) + " labels for " +
                     std::to_string(tets.rows()) + " tets");
  return sample_labels(TetLocator(vertices, tets), tet_labels, points, outside_label, outside_tolerance);
}

std::vector<int> sample_labels(const TetLocator& at, const std::vector<int>& tet_labels, const Points& points,
                               int outside_label, double outside_tolerance) {
  if (static_cast<long>(tet_labels.size()) != at.tets().rows())
    throw InputError("sample_labels: " + std::to_string(tet_labels.size()) + " labels for " +
                     std::to_string(at.tets().rows()) + " tets");
  const std::vector<Location> loc = at.locate_all(points);
  std::vector<int> out(loc.size(), outside_label);
  for (size_t i = 0; i < loc.size(); ++i)
    if (loc[i].tet >= 0 && loc[i].min_bary >= -outside_tolerance) out[i] = tet_labels[loc[i].tet];
  return out;
}

std::vector<LabelOverlap> dice_overlap(const std::vector<int>& a, const std::vector<int>& b,
                                       const std::vector<int>& labels) {
  if (a.size() != b.size())
    throw InputError("dice_overlap: samplings of different lengths (" + std::to_string(a.size()) + " and " +
                     std::to_string(b.size()) + ")");
  std::vector<LabelOverlap> out(labels.size());
  std::unordered_map<int, size_t> slot;  // one pass over the points for all labels
  for (size_t l = 0; l < labels.size(); ++l) {
    out[l].label = labels[l];
    slot.emplace(labels[l], l);
  }
  for (size_t i = 0; i < a.size(); ++i) {
    const auto ia = slot.find(a[i]), ib = a[i] == b[i] ? ia : slot.find(b[i]);
    if (ia != slot.end()) {
      ++out[ia->second].count_a;
      if (a[i] == b[i]) ++out[ia->second].both;
    }
    if (ib != slot.end()) ++out[ib->second].count_b;
  }
  for (LabelOverlap& o : out) {
    // a label listed twice gets the counts of its first entry, as before
    const LabelOverlap& first = out[slot.at(o.label)];
    o.count_a = first.count_a, o.count_b = first.count_b, o.both = first.both;
    o.dice = o.count_a + o.count_b == 0 ? 1.0 : 2.0 * o.both / double(o.count_a + o.count_b);
  }
  return out;
}

}  // namespace vpm
