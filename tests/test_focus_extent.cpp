// The extent of a focus (CompareOptions::relative_extent): a ball of lowered uptake blurred by a
// known Gaussian, planted in the canonical elements with noise, is drawn at its own volume
// whatever its amplitude; a fixed |z| level (the hysteresis alone) draws the strong one too large.
#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "vpm/elements.hpp"
#include "vpm/statistics.hpp"

using namespace vpm;

namespace {

const double kPi = 3.14159265358979323846;

// A ball of radius R convolved with an isotropic Gaussian of standard deviation s, at distance r
// from its centre (1 deep inside, 0 far outside).
double blurred_ball(double r, double R, double s) {
  const double q = std::sqrt(2.0) * s;
  if (r < 1e-9) return std::erf(R / q) - std::sqrt(2.0 / kPi) * (R / s) * std::exp(-R * R / (2 * s * s));
  return 0.5 * (std::erf((R - r) / q) + std::erf((R + r) / q)) -
         s / (r * std::sqrt(2 * kPi)) * (std::exp(-(r - R) * (r - R) / (2 * s * s)) - std::exp(-(r + R) * (r + R) / (2 * s * s)));
}

ElementDefinition graded4() {
  ElementDefinition d;
  d.layout = ElementLayout::graded;
  d.level = 4;
  d.shells = graded_shells(4);
  d.samples = 8;
  return d;
}

// Normals: mean 1, spread `noise` everywhere (30 of them).
Reference flat_reference(const CanonicalElements& el, double noise) {
  Reference r;
  r.definition = el.definition();
  r.feature = "pet";
  r.normalisation = Normalisation::none;
  r.subjects = 30;
  r.mean.assign(el.size(), 1.0);
  r.std.assign(el.size(), noise);
  r.count.assign(el.size(), 30);
  return r;
}

// A patient with uptake lowered by `loss` over a ball (centre c, radius R) blurred by s, plus noise.
ElementTable patient(const CanonicalElements& el, const Eigen::Vector3d& c, double R, double s, double loss,
                     double noise, unsigned seed) {
  ElementTable t;
  t.definition = el.definition();
  t.subject = "sub-P";
  ElementFeature f;
  f.name = "pet";
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, noise);
  for (int e = 0; e < el.size(); ++e) {
    f.mean.push_back(1 - loss * blurred_ball((el.centre(e) - c).norm(), R, s) + g(rng));
    f.std.push_back(0);
    f.count.push_back(8);
  }
  t.features.push_back(f);
  return t;
}

// The volume drawn for the focus containing the element at c (0 when none does).
double drawn_volume(const CanonicalElements& el, const Comparison& cmp, const Eigen::Vector3d& c) {
  const int id = cmp.cluster[el.element_of(c)];
  return id > 0 ? cmp.clusters[id - 1].volume : 0;
}

}  // namespace

TEST_CASE("focus extent: a blurred focus is drawn at its own volume whatever its amplitude") {
  const CanonicalElements el(graded4());  // elements of about 0.05 ball units
  const double noise = 0.04, R = 0.2, s = 0.07;  // R / s = 2.9, as a 10 mm focus under 8 mm FWHM
  const Reference ref = flat_reference(el, noise);
  const Eigen::Vector3d c(0.1, 0.55, 0.3);
  const double truth = 4 * kPi / 3 * R * R * R;
  CompareOptions fixed;  // the hysteresis alone: cut 3, grown to 2.5, clusters >= 10
  fixed.min_cluster = 10;
  fixed.extend = 2.5;
  fixed.sign = -1;
  CompareOptions relative = fixed;
  relative.relative_extent = 0.3;  // the workflow's default
  for (double loss : {0.2, 0.3, 0.35, 0.4}) {  // peak z 5, 7.5, 8.75, 10
    double sum = 0;
    for (unsigned seed : {1u, 2u, 3u, 4u}) {
      INFO("loss " << loss << ", seed " << seed);
      const ElementTable p = patient(el, c, R, s, loss, noise, seed);
      const double v = drawn_volume(el, compare_to_reference(el, ref, p, relative), c) / truth;
      const double v_fixed = drawn_volume(el, compare_to_reference(el, ref, p, fixed), c) / truth;
      CHECK(v <= v_fixed);  // the rule only trims what the hysteresis drew
      if (loss == 0.2) {
        // a weak focus: its edge (z 1.9) is under the hysteresis level, both draw its core only
        // (or, in one draw of the noise, find no focus of 10 elements at z >= 3)
        CHECK(v < 0.75);
        CHECK(v_fixed < 0.75);
        continue;
      }
      CHECK(std::abs(v - 1) < (loss == 0.4 ? 0.2 : 0.15));
      if (loss >= 0.35) CHECK(v_fixed > 1.25);  // a fixed level follows the blur's tail
      sum += v;
    }
    if (loss == 0.3 || loss == 0.35) CHECK(std::abs(sum / 4 - 1) < 0.1);  // the volume, on average
  }
}

TEST_CASE("focus extent: which foci are found and their candidates do not change") {
  const CanonicalElements el(graded4());
  const Reference ref = flat_reference(el, 0.04);
  const Eigen::Vector3d c(-0.4, 0.2, -0.5);
  const ElementTable p = patient(el, c, 0.15, 0.05, 0.35, 0.04, 7);
  CompareOptions o;
  o.min_cluster = 10;
  o.extend = 2.5;
  const Comparison plain = compare_to_reference(el, ref, p, o);
  o.relative_extent = 0.5;
  const Comparison rel = compare_to_reference(el, ref, p, o);
  REQUIRE(plain.clusters.size() == rel.clusters.size());
  REQUIRE(!rel.clusters.empty());
  for (size_t i = 0; i < rel.clusters.size(); ++i) {
    CHECK(rel.clusters[i].candidates == plain.clusters[i].candidates);
    CHECK(rel.clusters[i].peak_element == plain.clusters[i].peak_element);
    CHECK(rel.clusters[i].elements.size() < plain.clusters[i].elements.size());
    for (int e : rel.clusters[i].elements) CHECK(plain.cluster[e] == plain.clusters[i].id);
  }
  // every element kept reaches the focus's level: none under the hysteresis level
  for (int e : rel.clusters[0].elements) CHECK(-rel.z[e] >= 2.5);
}
