#include "vpm/statistics.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <numeric>

#include "collective/covariate_model.hpp"
#include "collective/comparison.hpp"
#include "collective/distributions.hpp"
#include "vpm/error.hpp"
#include "vpm/tfce.hpp"

namespace vpm {

namespace {
const double kNaN = std::numeric_limits<double>::quiet_NaN();
}  // namespace

Normalisation parse_normalisation(const std::string& name) {
  if (name == "none") return Normalisation::none;
  if (name == "proportional") return Normalisation::proportional;
  throw InputError("normalisation '" + name + "' is not one of none, proportional");
}

const char* to_string(Normalisation n) { return n == Normalisation::none ? "none" : "proportional"; }

SingleCaseTest parse_single_case_test(const std::string& name) {
  if (name == "z") return SingleCaseTest::z;
  if (name == "crawford-howell") return SingleCaseTest::crawford_howell;
  throw InputError("test '" + name + "' is not one of z, crawford-howell");
}

const char* to_string(SingleCaseTest t) { return t == SingleCaseTest::z ? "z" : "crawford-howell"; }

std::vector<double> normalised_feature(const ElementTable& t, const std::string& name, Normalisation n) {
  const auto f = std::find_if(t.features.begin(), t.features.end(), [&](const ElementFeature& x) { return x.name == name; });
  if (f == t.features.end()) throw InputError(t.subject + ": no feature '" + name + "' in the table");
  double sum = 0, count = 0;
  for (size_t e = 0; e < f->mean.size(); ++e) {
    sum += f->mean[e] * f->count[e];
    count += f->count[e];
  }
  const double scale = n == Normalisation::proportional && sum != 0 ? count / sum : 1.0;
  std::vector<double> v(f->mean.size());
  for (size_t e = 0; e < v.size(); ++e) v[e] = f->count[e] > 0 ? f->mean[e] * scale : kNaN;
  return v;
}

std::vector<double> smooth_over_elements(const CanonicalElements& el, const std::vector<double>& values, int rings) {
  if (rings <= 0) return values;
  if (static_cast<int>(values.size()) != el.size())
    throw InputError("smoothing: " + std::to_string(values.size()) + " values for " + std::to_string(el.size()) + " elements");
  std::vector<double> out(values.size(), kNaN);
  std::vector<int> mark(values.size(), -1), ring, next;
  const CanonicalElements::Adjacency& adj = el.adjacency();
  for (int e = 0; e < el.size(); ++e) {
    if (std::isnan(values[e])) continue;
    double sum = 0, weight = 0;
    ring.assign(1, e);
    mark[e] = e;
    for (int r = 0; r <= rings && !ring.empty(); ++r) {
      next.clear();
      for (int a : ring) {
        if (!std::isnan(values[a])) {
          sum += el.volume(a) * values[a];
          weight += el.volume(a);
        }
        if (r < rings)
          for (int b : adj.of(a))
            if (mark[b] != e) {
              mark[b] = e;
              next.push_back(b);
            }
      }
      ring.swap(next);
    }
    out[e] = sum / weight;
  }
  return out;
}

Reference build_reference(const std::vector<ElementTable>& normals, const std::vector<std::string>& names,
                          const std::string& feature, Normalisation normalisation) {
  if (normals.size() < 3) throw InputError("reference: needs at least 3 normals, got " + std::to_string(normals.size()));
  ReferenceRecipe recipe;
  recipe.feature = feature;
  recipe.normalisation = normalisation;
  return sum_normals(normals[0].definition, recipe, tables_in_memory(normals, names, recipe, nullptr)).reference(nullptr, 0);
}

Reference build_reference(const CanonicalElements& elements, const std::vector<ElementTable>& normals,
                          const std::vector<std::string>& names, const std::string& feature, Normalisation normalisation,
                          int smoothing, double shrinkage, const CovariateDesign& covariates,
                          const std::string& image_covariate) {
  if (normals.size() < 3) throw InputError("reference: needs at least 3 normals, got " + std::to_string(normals.size()));
  if (!(shrinkage >= 0 && shrinkage <= 1))
    throw InputError("reference: shrinkage " + std::to_string(shrinkage) + " is not in [0, 1]");
  const ReferenceRecipe recipe = reference_recipe(feature, normalisation, smoothing, image_covariate, covariates);
  return sum_normals(normals[0].definition, recipe, tables_in_memory(normals, names, recipe, &elements, covariates))
      .reference(&elements, shrinkage);
}

namespace {

// The z with the same tail probability as Student's t with `dof` degrees of freedom.
double t_as_z(double t, double dof) {
  const double z = detail::normal_lower_quantile(detail::student_t_tail(t, dof));  // <= 0
  return t < 0 ? z : -z;
}

// The z with the same tail probability as Crawford and Howell's t of a single case against n
// normals (n - 1 degrees of freedom); plain z when n is 0 (a reference written before counts).
double crawford_howell_z(double x, double mean, double std, int n) {
  if (n < 2) return (x - mean) / std;
  return t_as_z((x - mean) / (std * std::sqrt((n + 1.0) / n)), n - 1.0);
}

// z of the patient's values x against a reference with a model (its design row `row`, its
// values of the image covariate `image`; empty without one).
void covariate_z(const Reference& ref, const std::vector<double>& row, const std::vector<double>& image,
                 SingleCaseTest test, Comparison& c) {
  const std::vector<double>& x = c.patient;
  const double q = ref.model_columns();
  for (size_t e = 0; e < x.size(); ++e) {
    if (std::isnan(ref.mean[e])) continue;
    const double own = image.empty() ? 0.0 : image[e];
    if (std::isnan(own)) continue;
    const detail::ModelPrediction p = detail::predict(ref, static_cast<int>(e), row, own);
    c.expected[e] = p.expected;
    if (std::isnan(x[e]) || !(ref.std[e] > 0)) continue;
    // the z test takes the normals' mean at their centre as exact (as without covariates) but
    // not the slopes: their uncertainty grows with the patient's distance from the centre,
    // h - 1/n; Crawford-Howell counts both (h) with n - p - 1 degrees of freedom
    c.z[e] = test == SingleCaseTest::z
                 ? (x[e] - p.expected) / (ref.std[e] * std::sqrt(1.0 + std::max(0.0, p.leverage - 1.0 / ref.count[e])))
                 : t_as_z((x[e] - p.expected) / (ref.std[e] * std::sqrt(1.0 + p.leverage)), ref.count[e] - q);
  }
}

// Benjamini-Hochberg: the smallest |z| whose two-sided p-value passes at rate q (infinity when
// none does). Candidates are limited to the requested sign.
double fdr_threshold(const std::vector<double>& z, double q, int sign) {
  std::vector<double> p;
  for (double v : z)
    if (!std::isnan(v) && (sign == 0 || v * sign > 0)) p.push_back(std::erfc(std::abs(v) / std::sqrt(2.0)));
  std::sort(p.begin(), p.end());
  double cut = -1;
  for (size_t i = 0; i < p.size(); ++i)
    if (p[i] <= q * double(i + 1) / double(p.size())) cut = p[i];
  if (cut < 0) return std::numeric_limits<double>::infinity();
  // |z| with erfc(|z| / sqrt 2) == cut, by bisection
  double lo = 0, hi = 40;
  for (int it = 0; it < 200; ++it) {
    const double mid = 0.5 * (lo + hi);
    (std::erfc(mid / std::sqrt(2.0)) > cut ? lo : hi) = mid;
  }
  return hi;
}

// A gathered cluster's elements sorted, its volume and its peak |z| (of its sign).
void finish(const CanonicalElements& el, const std::vector<double>& z, FocusCluster& c) {
  std::sort(c.elements.begin(), c.elements.end());
  for (int e : c.elements) {
    c.volume += el.volume(e);
    if (c.peak_element < 0 || z[e] * c.sign > c.peak_z * c.sign) {
      c.peak_element = e;
      c.peak_z = z[e];
    }
  }
}

// Connected components of the elements of one sign with sign * z >= low; a component is a focus
// when at least min_size of its elements reach `cut` (low == cut: plain clusters of candidates),
// or when one reaches `peak` (> 0; and `cut`).
std::vector<FocusCluster> clusters_of(const CanonicalElements& el, const std::vector<double>& z, double cut, double low,
                                      int sign, int min_size, double peak) {
  const int n = el.size();
  std::vector<char> seen(n, 0);
  std::vector<FocusCluster> out;
  const CanonicalElements::Adjacency& adj = el.adjacency();
  auto in = [&](int e) { return !std::isnan(z[e]) && z[e] * sign >= low; };
  for (int s0 = 0; s0 < n; ++s0) {
    if (seen[s0] || !in(s0)) continue;
    FocusCluster c;
    c.sign = sign;
    std::vector<int> stack{s0};
    seen[s0] = 1;
    int core = 0;
    double top = 0;
    while (!stack.empty()) {
      const int e = stack.back();
      stack.pop_back();
      c.elements.push_back(e);
      core += z[e] * sign >= cut;
      top = std::max(top, z[e] * sign);
      for (int nb : adj.of(e))
        if (!seen[nb] && in(nb)) {
          seen[nb] = 1;
          stack.push_back(nb);
        }
    }
    if (core < min_size && !(peak > 0 && core > 0 && top >= peak)) continue;
    c.candidates = core;
    finish(el, z, c);
    out.push_back(std::move(c));
  }
  return out;
}

// CompareOptions::relative_extent: focus c (its elements reach the hysteresis level already)
// redrawn over its elements whose local mean of sign * z (over the element and its adjacent
// elements: z's unit noise per element would otherwise jitter the edge outwards) reaches
// fraction x the largest such mean in the focus, connected through such elements to its peak.
void delineate(const CanonicalElements& el, const std::vector<double>& z, double fraction, FocusCluster& c) {
  const CanonicalElements::Adjacency& adj = el.adjacency();
  std::vector<double> local(c.elements.size());
  double top = 0;
  for (size_t i = 0; i < c.elements.size(); ++i) {
    const int e = c.elements[i];
    double sum = z[e] * c.sign;
    int n = 1;
    for (int nb : adj.of(e))
      if (!std::isnan(z[nb])) sum += z[nb] * c.sign, ++n;
    local[i] = sum / n;
    top = std::max(top, local[i]);
  }
  const double level = fraction * top;
  std::vector<int> stack, kept;
  std::vector<char> seen(c.elements.size(), 0);
  const auto visit = [&](int e) {
    const auto at = std::lower_bound(c.elements.begin(), c.elements.end(), e);
    if (at == c.elements.end() || *at != e) return;
    const size_t i = static_cast<size_t>(at - c.elements.begin());
    if (seen[i] || (local[i] < level && e != c.peak_element)) return;
    seen[i] = 1;
    stack.push_back(e);
  };
  visit(c.peak_element);
  while (!stack.empty()) {
    const int e = stack.back();
    stack.pop_back();
    kept.push_back(e);
    for (int nb : adj.of(e)) visit(nb);
  }
  std::sort(kept.begin(), kept.end());
  c.elements = std::move(kept);
  c.volume = 0;
  for (int e : c.elements) c.volume += el.volume(e);
}

// CompareOptions::tfce_level: the foci are the connected sets of elements of one sign with
// sign * z >= low (the hysteresis level; without one, the TFCE-significant elements alone) that
// hold an element whose TFCE score reaches the level: TFCE tells which foci there are, z their
// extent. Each has its peak |z|, its highest score and its significant elements as candidates.
std::vector<FocusCluster> tfce_clusters(const CanonicalElements& el, const std::vector<double>& z, int sign,
                                        double level, double low) {
  const std::vector<double> score = tfce_scores(el, z, sign);
  const int n = el.size();
  const CanonicalElements::Adjacency& adj = el.adjacency();
  auto in = [&](int e) { return score[e] >= level || (low > 0 && !std::isnan(z[e]) && z[e] * sign >= low); };
  std::vector<char> seen(n, 0);
  std::vector<FocusCluster> out;
  for (int s0 = 0; s0 < n; ++s0) {
    if (seen[s0] || score[s0] < level) continue;  // grown from a significant element
    FocusCluster c;
    c.sign = sign;
    std::vector<int> stack{s0};
    seen[s0] = 1;
    while (!stack.empty()) {
      const int e = stack.back();
      stack.pop_back();
      c.elements.push_back(e);
      c.candidates += score[e] >= level;
      c.peak_tfce = std::max(c.peak_tfce, score[e]);
      for (int nb : adj.of(e))
        if (!seen[nb] && in(nb)) {
          seen[nb] = 1;
          stack.push_back(nb);
        }
    }
    finish(el, z, c);
    out.push_back(std::move(c));
  }
  return out;
}

}  // namespace

Comparison compare_to_reference(const CanonicalElements& el, const Reference& ref, const ElementTable& patient,
                                const CompareOptions& opt, const std::vector<double>& covariates) {
  if (patient.definition != ref.definition || el.definition() != ref.definition)
    throw InputError(patient.subject + ": element definition differs from the reference's");
  return detail::compare_values(el, ref, normal_values(&el, patient, patient.subject, detail::recipe_of(ref)), opt,
                                covariates, patient.subject);
}

namespace detail {

ReferenceRecipe recipe_of(const Reference& ref) {
  ReferenceRecipe r;
  r.feature = ref.feature;
  r.normalisation = ref.normalisation;
  r.smoothing = ref.smoothing;
  r.image_covariate = ref.image_covariate;
  r.covariates = ref.covariate_names;
  r.covariate_columns = ref.covariates;
  r.covariate_table = ref.covariate_table;
  return r;
}

Comparison compare_values(const CanonicalElements& el, const Reference& ref, const NormalValues& values,
                          const CompareOptions& opt, const std::vector<double>& covariates, const std::string& who) {
  if (el.definition() != ref.definition) throw InputError(who + ": element definition differs from the reference's");
  if (covariates.size() != ref.covariates.size())
    throw InputError(who + ": " + std::to_string(covariates.size()) + " covariate values for a reference of " +
                     std::to_string(ref.covariates.size()) + " covariates");
  if (const auto bad = compare_option_error(opt)) throw InputError("compare options: " + bad->field + ": " + bad->problem);
  Comparison c;
  c.patient = values.feature;
  const std::vector<double>& x = c.patient;
  c.z.assign(x.size(), kNaN);
  if (ref.has_model()) {
    c.covariates = covariates;
    c.expected.assign(x.size(), kNaN);
    covariate_z(ref, covariates, values.image, opt.test, c);
  } else {
    c.expected = ref.mean;
    for (size_t e = 0; e < x.size(); ++e)
      if (!std::isnan(x[e]) && !std::isnan(ref.mean[e]) && ref.std[e] > 0)
        c.z[e] = opt.test == SingleCaseTest::z ? (x[e] - ref.mean[e]) / ref.std[e]
                                               : crawford_howell_z(x[e], ref.mean[e], ref.std[e],
                                                                   ref.count.empty() ? 0 : ref.count[e]);
  }
  c.threshold_used = opt.fdr_q > 0 ? fdr_threshold(c.z, opt.fdr_q, opt.sign) : opt.threshold;
  for (int sign : {1, -1}) {
    if (opt.sign != 0 && opt.sign != sign) continue;
    if (opt.tfce_level > 0) {
      for (FocusCluster& f : tfce_clusters(el, c.z, sign, opt.tfce_level, opt.extend)) {
        if (opt.relative_extent > 0) delineate(el, c.z, opt.relative_extent, f);
        c.clusters.push_back(std::move(f));
      }
      continue;
    }
    const double low = opt.extend > 0 ? std::min(opt.extend, c.threshold_used) : c.threshold_used;
    for (FocusCluster& f : clusters_of(el, c.z, c.threshold_used, low, sign, opt.min_cluster, opt.peak)) {
      if (opt.relative_extent > 0) delineate(el, c.z, opt.relative_extent, f);
      c.clusters.push_back(std::move(f));
    }
  }
  std::stable_sort(c.clusters.begin(), c.clusters.end(),
                   [](const FocusCluster& a, const FocusCluster& b) { return a.elements.size() > b.elements.size(); });
  c.cluster.assign(x.size(), 0);
  for (size_t i = 0; i < c.clusters.size(); ++i) {
    c.clusters[i].id = static_cast<int>(i) + 1;
    for (int e : c.clusters[i].elements) c.cluster[e] = c.clusters[i].id;
  }
  return c;
}

}  // namespace detail

Json to_json(const Comparison& c) {
  Json j = Json::object();
  j["threshold"] = c.threshold_used;
  Json list = Json::array();
  for (const FocusCluster& f : c.clusters) {
    Json o = Json::object();
    o["id"] = f.id;
    o["sign"] = f.sign;
    o["elements"] = static_cast<long>(f.elements.size());
    o["candidates"] = f.candidates;
    o["volume"] = f.volume;
    o["peak_element"] = f.peak_element;
    o["peak_z"] = f.peak_z;
    if (f.peak_tfce > 0) o["peak_tfce"] = f.peak_tfce;
    if (f.p_family >= 0) o["p_family"] = f.p_family;
    list.push_back(o);
  }
  j["clusters"] = list;
  return j;
}

}  // namespace vpm
