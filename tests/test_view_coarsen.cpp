// A page drawn at a coarser level than its tables (collective/view_coarsen.hpp,
// CohortViewOptions::max_display_level): each fine element belongs to the display element holding
// its centre, and values, spreads, counts and foci are carried there without losing a focus's
// volume or shifting a value.
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "collective/view_coarsen.hpp"

using namespace vpm;
using detail::ElementCoarsening;

namespace {

ElementDefinition graded(int level) {
  ElementDefinition d;
  d.level = level;
  d.shells = graded_shells(level);
  d.samples = 4;
  d.layout = ElementLayout::graded;
  return d;
}

}  // namespace

TEST_CASE("the display definition caps the level and keeps the layout's shells") {
  const ElementDefinition d = detail::display_definition(graded(6), 5);
  CHECK(d.level == 5);
  CHECK(d.shells == graded_shells(5));
  CHECK(d.samples == 4);
  CHECK(detail::display_definition(graded(4), 5) == graded(4));
  ElementDefinition shells{6, 12, 8, ElementLayout::shells};
  CHECK(detail::display_definition(shells, 5) == ElementDefinition{5, 12, 8, ElementLayout::shells});
}

TEST_CASE("display elements hold their fine elements' centres, and carry values, spreads, counts and foci") {
  const CanonicalElements fine(graded(4)), coarse(graded(3));
  const ElementCoarsening to(fine, coarse);
  REQUIRE(!to.identity());
  std::vector<int> children(static_cast<size_t>(coarse.size()), 0);
  for (int e = 0; e < fine.size(); ++e) {
    REQUIRE(to.of(e) == coarse.element_of(fine.centre(e)));
    ++children[static_cast<size_t>(to.of(e))];
  }
  for (int n : children) CHECK(n >= 1);  // no display element left without data
  // a value's total over the ball is kept (equal volumes): sum of child means x children
  std::vector<float> x(static_cast<size_t>(fine.size()));
  for (int e = 0; e < fine.size(); ++e) x[static_cast<size_t>(e)] = static_cast<float>(fine.centre(e).x() + 0.01 * (e % 7));
  x[5] = std::numeric_limits<float>::quiet_NaN();  // no data: skipped, not spread
  const std::vector<float> m = to.mean(x);
  REQUIRE(static_cast<int>(m.size()) == coarse.size());
  double fine_sum = 0, coarse_sum = 0;
  for (int e = 0; e < fine.size(); ++e)
    if (e != 5) fine_sum += x[static_cast<size_t>(e)];
  std::vector<int> finite(children);
  --finite[static_cast<size_t>(to.of(5))];
  for (int c = 0; c < coarse.size(); ++c) coarse_sum += finite[static_cast<size_t>(c)] * double(m[static_cast<size_t>(c)]);
  CHECK(coarse_sum == Approx(fine_sum).margin(1e-3));
  // a linear field's mean lands near the display element's own centre
  for (int c = 0; c < coarse.size(); c += 97) CHECK(std::abs(m[static_cast<size_t>(c)] - coarse.centre(c).x()) < 0.08);
  // spreads by root mean square, counts the least
  std::vector<float> s(x.size(), 2.0f);
  s[0] = 1.0f;
  const int first = to.of(0);
  const double n0 = children[static_cast<size_t>(first)];
  CHECK(to.rms(s)[static_cast<size_t>(first)] == Approx(std::sqrt((1.0 + 4.0 * (n0 - 1)) / n0)));
  std::vector<int> count(x.size(), 30);
  count[0] = 29;
  CHECK(to.least(count)[static_cast<size_t>(first)] == 29);
  CHECK(to.least(count)[static_cast<size_t>((first + 1) % coarse.size())] == 30 - (to.of(0) == (first + 1) % coarse.size()));
  // a focus (the fine elements within 0.35 of a point) keeps its volume within a display
  // element's rim, and a display element goes to the focus when at least half its elements are in it
  const Eigen::Vector3d p(0.3, -0.2, 0.4);
  std::vector<std::int32_t> id(x.size(), 0);
  double fine_volume = 0, coarse_volume = 0;
  for (int e = 0; e < fine.size(); ++e)
    if ((fine.centre(e) - p).norm() < 0.35) id[static_cast<size_t>(e)] = 3, fine_volume += fine.volume(e);
  const std::vector<std::int32_t> cid = to.most_frequent(id);
  std::vector<int> in(static_cast<size_t>(coarse.size()), 0);
  for (int e = 0; e < fine.size(); ++e) in[static_cast<size_t>(to.of(e))] += id[static_cast<size_t>(e)] == 3;
  for (int c = 0; c < coarse.size(); ++c) {
    CHECK(cid[static_cast<size_t>(c)] == (2 * in[static_cast<size_t>(c)] >= children[static_cast<size_t>(c)] ? 3 : 0));
    if (cid[static_cast<size_t>(c)] == 3) coarse_volume += coarse.volume(c);
  }
  CHECK(coarse_volume == Approx(fine_volume).epsilon(0.15));
}

TEST_CASE("the same definition is the identity") {
  const CanonicalElements el(graded(3));
  const ElementCoarsening to(el, el);
  CHECK(to.identity());
  const std::vector<float> x{1.0f, 2.0f};
  CHECK(to.mean(x) == x);
  CHECK(to.of(7) == 7);
}
