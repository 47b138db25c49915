#include "support/elements.hpp"

#include <random>

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

ElementTable noisy_pet_table(const std::string& id, unsigned seed, const std::set<int>& focus, double loss) {
  const CanonicalElements el(small_elements());
  ElementTable t;
  t.definition = el.definition();
  t.subject = id;
  ElementFeature f;
  f.name = "pet";
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(100, 5);
  for (int e = 0; e < el.size(); ++e) {
    f.mean.push_back(g(rng) - (focus.count(e) ? loss : 0));
    f.std.push_back(1);
    f.count.push_back(8);
  }
  t.features.push_back(f);
  return t;
}

Reference reference_without(const CanonicalElements& elements, const std::vector<ElementTable>& normals,
                            const std::vector<std::string>& names, size_t left_out, Normalisation normalisation) {
  std::vector<ElementTable> others;
  std::vector<std::string> other_names;
  for (size_t j = 0; j < normals.size(); ++j)
    if (j != left_out) others.push_back(normals[j]), other_names.push_back(names[j]);
  return build_reference(elements, others, other_names, "pet", normalisation, 0);
}

}  // namespace vpm::test
