#include "support/elements.hpp"

namespace vpm::test {

ElementDefinition small_elements() {
  ElementDefinition d;
  d.level = 2;
  d.shells = 3;
  d.samples = 8;
  return d;
}

std::set<int> planted_focus(const CanonicalElements& elements, int e0) {
  std::set<int> s{e0};
  for (int n : elements.neighbours(e0))
    if (elements.shell_of(n) == elements.shell_of(e0)) s.insert(n);
  return s;
}

}  // namespace vpm::test
