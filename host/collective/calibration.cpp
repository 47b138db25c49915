// Leave-one-normal-out calibration of the cluster-extent threshold (vpm/calibration.hpp).
#include "vpm/calibration.hpp"

#include <algorithm>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
#include <map>

#include "collective/comparison.hpp"
#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/tfce.hpp"

namespace vpm {

namespace {

// The clusters of normal `values` (normals()[index] of the totals) compared with the reference of
// the others at min_cluster 1: (candidates, peak_z) each.
// With s.calibrate_tfce, `tfce_max` is set to the normal's highest TFCE score over the signs compared.
std::vector<std::pair<int, double>> leave_out(const CanonicalElements& el, const ReferenceSums& totals, size_t index,
                                              const NormalValues& values, const CalibrationSettings& s,
                                              double& tfce_max) {
  const Reference ref = totals.reference_without(&el, s.shrinkage, index, values);
  CompareOptions o = s.compare;
  o.min_cluster = 1;
  const Comparison c = detail::compare_values(el, ref, values, o, totals.design()[index], totals.normals()[index]);
  std::vector<std::pair<int, double>> out;
  for (const FocusCluster& f : c.clusters) out.emplace_back(f.candidates, f.peak_z);
  tfce_max = 0;
  if (s.calibrate_tfce)
    for (int sign : {1, -1})
      if (s.compare.sign == 0 || s.compare.sign == sign)
        for (double v : tfce_scores(el, c.z, sign)) tfce_max = std::max(tfce_max, v);
  return out;
}

// CalibrationSettings::calibrate_tfce's level: strictly beyond the (k + 1)-th highest maximum;
// every normal may pass when k >= their number (the lowest positive score then).
double calibrated_tfce(const std::vector<LeftOutNormal>& per_normal, size_t k) {
  std::vector<double> maxima;
  for (const LeftOutNormal& n : per_normal) maxima.push_back(n.tfce_max);
  std::sort(maxima.begin(), maxima.end(), std::greater<>());
  const TfceParameters p;
  const double lowest = std::pow(p.step, p.height_power) * p.step;  // one element at the first height
  if (k >= maxima.size()) return lowest;
  if (!(maxima[k] > 0)) return lowest;
  // the next step of the 6th significant digit: strictly beyond, and kept by the JSON's 10 digits
  const double q = std::pow(10.0, std::floor(std::log10(maxima[k])) - 5.0);
  return std::max(lowest, (std::floor(maxima[k] / q) + 1.0) * q);
}

// The order of strong clusters: highest |peak_z| first, ties by normal, then candidates (a total
// order, so the k + 1 kept do not depend on how the normals were split among threads).
bool stronger(const StrongCluster& a, const StrongCluster& b) {
  const double pa = std::abs(a.peak_z), pb = std::abs(b.peak_z);
  if (pa != pb) return pa > pb;
  if (a.normal != b.normal) return a.normal < b.normal;
  return a.candidates > b.candidates;
}

// What one thread gathers from its normals left out: the sizes' histogram and the strong clusters.
struct Gathered {
  std::vector<long> sizes;
  std::vector<StrongCluster> strong;
  // keep the first `keep` by stronger() (all that reach `fixed` when it is > 0)
  void add(int normal, int candidates, double peak_z, size_t keep, double fixed) {
    if (static_cast<size_t>(candidates) >= sizes.size()) sizes.resize(static_cast<size_t>(candidates) + 1, 0);
    ++sizes[static_cast<size_t>(candidates)];
    if (candidates <= 0) return;
    if (fixed > 0) {
      if (std::abs(peak_z) >= fixed) strong.push_back({normal, candidates, peak_z});
      return;
    }
    if (keep == 0) return;
    strong.push_back({normal, candidates, peak_z});
    if (strong.size() >= 2 * keep) prune(keep);
  }
  void prune(size_t keep) {
    std::sort(strong.begin(), strong.end(), stronger);
    if (strong.size() > keep) strong.resize(keep);
  }
};

// CalibrationSettings::calibrate_peak's level: at most half the rate's clusters (over all
// normals left out) peak at or beyond it; `k` those clusters, `strong` the k + 1 strongest.
double calibrated_peak(const ClusterCalibration& cal, size_t k, const CalibrationSettings& s) {
  long total = 0;
  for (size_t c = 1; c < cal.sizes.size(); ++c) total += cal.sizes[c];
  if (k >= static_cast<size_t>(total)) return s.compare.threshold;  // every cluster may pass
  const double kth = std::abs(cal.strong[k].peak_z);
  if (!std::isfinite(kth)) return 0;  // no level is beyond it (a reference without spread): off
  const double level = (std::floor(kth * 100.0 + 1e-9) + 1.0) / 100.0;  // the next 0.01 step
  return std::max(level, std::nextafter(kth, HUGE_VAL));               // strictly beyond the (k+1)-th
}

}  // namespace

long ClusterCalibration::clusters_at(int m) const {
  m = std::max(m, 1);
  long count = 0;
  for (size_t c = static_cast<size_t>(m); c < sizes.size(); ++c) count += sizes[c];
  if (peak > 0)  // the small clusters the peak rule keeps (every one reaching the level is in strong)
    for (const StrongCluster& c : strong) count += c.candidates > 0 && c.candidates < m && std::abs(c.peak_z) >= peak;
  return count;
}

double ClusterCalibration::rate_at(int m) const { return normals > 0 ? 10.0 * double(clusters_at(m)) / normals : 0; }

ClusterCalibration calibrate_min_cluster(const CanonicalElements& el, const ReferenceSums& totals,
                                         const NormalSource& left_out, const CalibrationSettings& s) {
  if (totals.normals().size() < 4)
    throw InputError("calibration: needs at least 4 normals (3 in each reference), got " +
                     std::to_string(totals.normals().size()));
  if (!(s.rate >= 0)) throw InputError("calibration: the rate must be >= 0 false clusters per 10 normals");
  if (s.calibrate_peak && s.compare.peak != 0)
    throw InputError("calibration: a fixed peak level and a calibrated one exclude each other");
  if (s.calibrate_tfce && (s.calibrate_peak || s.compare.peak != 0 || s.compare.tfce_level != 0))
    throw InputError("calibration: a TFCE level is calibrated without a peak rule or a fixed TFCE level");
  ReferenceRecipe wanted = totals.recipe();  // the settings' recipe, with the sums' covariate columns
  wanted.feature = s.feature;
  wanted.normalisation = s.normalisation;
  wanted.smoothing = s.smoothing;
  wanted.image_covariate = s.image_covariate;
  wanted.covariates = s.covariates;
  if (const auto diff = recipe_difference(wanted, totals.recipe()))
    throw InputError("calibration: the reference sums were made with " + *diff);
  std::map<std::string, size_t> index;
  for (size_t i = 0; i < totals.normals().size(); ++i) index.emplace(totals.normals()[i], i);
  for (const std::string& name : left_out.names)
    if (!index.count(name)) throw InputError(name + ": not one of the reference's normals (it cannot be left out of it)");
  ClusterCalibration cal;
  cal.settings = s;
  cal.normals = static_cast<int>(left_out.names.size());
  cal.per_normal.resize(left_out.names.size());
  // the clusters half the rate lets the peak rule keep
  const size_t k = static_cast<size_t>(std::floor(0.5 * s.rate * static_cast<double>(cal.normals) / 10.0 + 1e-12));
  const size_t keep = s.calibrate_peak ? k + 1 : 0;
  const int threads = detail::host_threads();
  std::vector<Gathered> gathered(static_cast<size_t>(threads));
  std::vector<std::exception_ptr> errors(left_out.names.size());  // the first normal's is rethrown as it was
  const int chunk = (cal.normals + threads - 1) / threads;
  detail::parallel_for(threads, 2, [&](int tb, int te) {
    for (int t = tb; t < te; ++t)
      for (int i = t * chunk; i < std::min(cal.normals, (t + 1) * chunk); ++i) try {
          const size_t n = static_cast<size_t>(i);
          const NormalValues v = left_out.values(n);
          double tfce_max = 0;
          const auto clusters = leave_out(el, totals, index.at(left_out.names[n]), v, s, tfce_max);
          LeftOutNormal& out = cal.per_normal[n];
          out = {left_out.names[n], static_cast<int>(clusters.size()), 0, 0.0, tfce_max};
          for (const auto& [candidates, peak_z] : clusters) {
            gathered[static_cast<size_t>(t)].add(i, candidates, peak_z, keep, s.compare.peak);
            out.largest = std::max(out.largest, candidates);
            out.strongest = std::max(out.strongest, std::abs(peak_z));
          }
        } catch (...) {
          errors[static_cast<size_t>(i)] = std::current_exception();
        }
  });
  for (const std::exception_ptr& x : errors)
    if (x) std::rethrow_exception(x);
  for (Gathered& g : gathered) {
    if (g.sizes.size() > cal.sizes.size()) cal.sizes.resize(g.sizes.size(), 0);
    for (size_t c = 0; c < g.sizes.size(); ++c) cal.sizes[c] += g.sizes[c];
    cal.strong.insert(cal.strong.end(), g.strong.begin(), g.strong.end());
  }
  std::sort(cal.strong.begin(), cal.strong.end(), stronger);
  if (keep > 0 && cal.strong.size() > keep) cal.strong.resize(keep);
  cal.peak = s.calibrate_peak ? calibrated_peak(cal, k, s) : s.compare.peak;
  if (s.calibrate_tfce)  // at most rate/10 of the normals over the level
    cal.tfce_level = calibrated_tfce(
        cal.per_normal, static_cast<size_t>(std::floor(s.rate * static_cast<double>(cal.normals) / 10.0 + 1e-12)));
  const int largest = static_cast<int>(cal.sizes.size()) - 1;
  for (int m = 1; m <= std::max(largest, 0) + 1; ++m) {
    cal.false_clusters.push_back(static_cast<int>(cal.clusters_at(m)));
    if (cal.min_cluster == 0 && cal.rate_at(m) <= s.rate) cal.min_cluster = m;
  }
  return cal;
}

ClusterCalibration calibrate_min_cluster(const CanonicalElements& el, const std::vector<ElementTable>& normals,
                                         const std::vector<std::string>& names, const CalibrationSettings& s,
                                         const CovariateDesign& design) {
  if (normals.size() != names.size()) throw InputError("calibration: names and tables differ in number");
  if (design.names != s.covariates || (!design.empty() && design.rows.size() != normals.size()))
    throw InputError("calibration: the covariate design does not match the settings' covariates or the normals");
  if (normals.size() < 4)
    throw InputError("calibration: needs at least 4 normals (3 in each reference), got " +
                     std::to_string(normals.size()));
  const ReferenceRecipe recipe = reference_recipe(s.feature, s.normalisation, s.smoothing, s.image_covariate, design);
  const NormalSource source = tables_in_memory(normals, names, recipe, &el, design);
  return calibrate_min_cluster(el, sum_normals(normals[0].definition, recipe, source), source, s);
}

namespace {

Json options_json(const CalibrationSettings& s) {
  Json o = Json::object();
  o["threshold"] = s.compare.threshold;
  o["fdr_q"] = s.compare.fdr_q;
  o["extend"] = s.compare.extend;
  o["peak"] = s.compare.peak;
  o["test"] = to_string(s.compare.test);
  o["sign"] = s.compare.sign;
  return o;
}

}  // namespace

Json to_json(const ClusterCalibration& c) {
  Json j = Json::object();
  j["feature"] = c.settings.feature;
  j["normalisation"] = to_string(c.settings.normalisation);
  j["smoothing"] = c.settings.smoothing;
  j["shrinkage"] = c.settings.shrinkage;
  Json cov = Json::array();
  for (const std::string& n : c.settings.covariates) cov.push_back(n);
  j["covariates"] = cov;
  j["image_covariate"] = c.settings.image_covariate;
  j["options"] = options_json(c.settings);
  j["rate"] = c.settings.rate;
  j["normals"] = c.normals;
  j["min_cluster"] = c.min_cluster;
  j["calibrate_peak"] = c.settings.calibrate_peak;
  j["peak"] = c.peak;
  Json curve = Json::array();
  for (size_t m = 1; m <= c.false_clusters.size(); ++m) {
    Json p = Json::object();
    p["min_cluster"] = static_cast<long>(m);
    p["false_clusters"] = c.false_clusters[m - 1];
    p["per_10_normals"] = c.rate_at(static_cast<int>(m));
    curve.push_back(p);
  }
  j["curve"] = curve;
  Json sizes = Json::array();
  for (long v : c.sizes) sizes.push_back(v);
  j["sizes"] = sizes;
  Json strong = Json::array();
  for (const StrongCluster& x : c.strong) {
    Json o = Json::object();
    o["normal"] = c.per_normal[static_cast<size_t>(x.normal)].name;
    o["candidates"] = x.candidates;
    o["peak_z"] = x.peak_z;
    strong.push_back(o);
  }
  j["strong"] = strong;
  Json per = Json::array();
  for (const LeftOutNormal& n : c.per_normal) {
    Json o = Json::object();
    o["normal"] = n.name;
    o["clusters"] = n.clusters;
    o["largest"] = n.largest;
    o["strongest"] = n.strongest;
    if (c.settings.calibrate_tfce) o["tfce_max"] = n.tfce_max;
    per.push_back(o);
  }
  j["per_normal"] = per;
  j["tfce"] = c.settings.calibrate_tfce;
  j["tfce_level"] = c.tfce_level;
  return j;
}

namespace {

const Json& member(const Json& j, const std::string& key, const std::string& source) {
  const Json* v = j.find(key);
  if (!v) throw InputError(source + ": not a calibration (no \"" + key + "\")");
  return *v;
}

// The setting `key` of the calibration equals `want` (numbers compared exactly: both written by
// vpm from the same decimal option).
void same(const Json& got, const Json& want, const std::string& key, const std::string& source) {
  const bool equal = got.type() == want.type() &&
                     (got.type() == Json::Type::String ? got.string() == want.string() : got.number() == want.number());
  if (!equal)
    throw InputError(source + ": calibrated with " + key + " " + got.dump(-1) + ", this comparison uses " +
                     want.dump(-1) + "; calibrate with the comparison's own options");
}


std::vector<std::string> calibrated_normals(const Json& cal, const std::string& source) {
  const Json& per = member(cal, "per_normal", source);
  std::vector<std::string> names;
  for (size_t i = 0; i < per.size(); ++i) {
    const Json* name = per.at(i).find("normal");
    if (!name || name->type() != Json::Type::String)
      throw InputError(source + ": per_normal[" + std::to_string(i) + "] names no normal");
    names.push_back(name->string());
  }
  std::sort(names.begin(), names.end());
  return names;
}

// `key` of a calibration file: absent (a file from before it) or false: false; else true or InputError.
bool optional_flag(const Json& cal, const char* key, const std::string& source) {
  const Json* v = cal.find(key);
  if (v && v->type() != Json::Type::Bool) throw InputError(source + ": \"" + key + "\" is not true or false");
  return v && v->boolean();
}

// The positive finite number at `key`, or InputError saying it is not `what`.
double positive_level(const Json& cal, const char* key, const char* what, const std::string& source) {
  const Json& v = member(cal, key, source);
  const double level = v.type() == Json::Type::Number ? v.number() : -1;
  if (!(level > 0 && std::isfinite(level))) throw InputError(source + ": \"" + key + "\" is not " + what);
  return level;
}

// Each normal's (largest, strongest) of per_normal; empty when a file from before them lacks
// them (no p-values then); InputError for values that are there but not counts or levels.
std::vector<std::pair<int, double>> cluster_null(const Json& per, const std::string& source) {
  std::vector<std::pair<int, double>> out;
  for (size_t i = 0; i < per.size(); ++i) {
    const Json* largest = per.at(i).find("largest");
    const Json* strongest = per.at(i).find("strongest");
    if (!largest && !strongest) return {};
    const double l = largest && largest->type() == Json::Type::Number ? largest->number() : -1;
    // null: an infinite |z| (a reference without spread there), as to_json writes it
    const double z = !strongest                                 ? -1
                     : strongest->type() == Json::Type::Number ? strongest->number()
                     : strongest->type() == Json::Type::Null   ? std::numeric_limits<double>::infinity()
                                                               : -1;
    if (!(l >= 0 && l <= 1e9 && l == std::floor(l)) || !(z >= 0))
      throw InputError(source + ": per_normal[" + std::to_string(i) +
                       "]: \"largest\" is not a count or \"strongest\" not a |z| level");
    out.emplace_back(static_cast<int>(l), z);
  }
  return out;
}

}  // namespace

CalibratedRule calibrated_rule(const Json& cal, const CalibrationSettings& s, const std::vector<std::string>& normals,
                               const std::string& source) {
  if (cal.type() != Json::Type::Object) throw InputError(source + ": not a calibration (not a JSON object)");
  CalibrationSettings probe = s;
  const Json want = to_json(ClusterCalibration{probe});
  for (const char* key : {"feature", "normalisation", "smoothing", "shrinkage"})
    same(member(cal, key, source), *want.find(key), key, source);
  const Json* cov = cal.find("covariates");  // absent before 2026-11-28: none
  if ((cov ? cov->dump(-1) : "[]") != want.find("covariates")->dump(-1))
    throw InputError(source + ": calibrated with covariates " + (cov ? cov->dump(-1) : "[]") + ", this comparison uses " +
                     want.find("covariates")->dump(-1) + "; calibrate with the comparison's own --covariates");
  const Json* image = cal.find("image_covariate");  // absent before 2026-11-29: none
  if (image && image->type() != Json::Type::String) throw InputError(source + ": \"image_covariate\" is not a string");
  const std::string image_name = image ? image->string() : "";
  if (image_name != s.image_covariate)
    throw InputError(source + ": calibrated with image covariate '" + image_name + "', this comparison uses '" +
                     s.image_covariate + "'; calibrate with the comparison's own --image-covariate");
  const Json& opts = member(cal, "options", source);
  for (const char* key : {"threshold", "fdr_q", "extend", "peak", "test", "sign"})
    same(member(opts, key, source), *want.find("options")->find(key), std::string("options.") + key, source);
  std::vector<std::string> want_normals = normals;
  std::sort(want_normals.begin(), want_normals.end());
  if (calibrated_normals(cal, source) != want_normals)
    throw InputError(source + ": calibrated on other normals (" + std::to_string(member(cal, "per_normal", source).size()) +
                     ") than this comparison's " + std::to_string(normals.size()) + "; calibrate on the same normals");
  const Json& m = member(cal, "min_cluster", source);
  const double v = m.type() == Json::Type::Number ? m.number() : -1;
  if (!(v >= 0 && v <= 1e9 && v == std::floor(v)))
    throw InputError(source + ": \"min_cluster\" is not a count");
  if (v == 0)
    throw InputError(source + ": the calibration found no min_cluster at or under its rate (a peak rule keeps "
                              "small clusters in the normals); lower the peak level or raise the rate");
  CalibratedRule rule{static_cast<int>(v), s.compare.peak};
  if (optional_flag(cal, "calibrate_peak", source))  // absent before 2026-11-29 (ninth session): no
    rule.peak = positive_level(cal, "peak", "a positive |z| level", source);
  if (optional_flag(cal, "tfce", source)) {  // absent before the TFCE calibration: none
    rule.tfce_level = positive_level(cal, "tfce_level", "a positive score", source);
    const Json& per = member(cal, "per_normal", source);
    for (size_t i = 0; i < per.size(); ++i) {
      const Json* m = per.at(i).find("tfce_max");
      const double v = m && m->type() == Json::Type::Number ? m->number() : -1;
      if (!(v >= 0 && std::isfinite(v)))
        throw InputError(source + ": per_normal[" + std::to_string(i) + "] has no \"tfce_max\" score");
      rule.tfce_null.push_back(v);
    }
    std::sort(rule.tfce_null.begin(), rule.tfce_null.end(), std::greater<>());
  } else {
    rule.cluster_null = cluster_null(member(cal, "per_normal", source), source);
  }
  return rule;
}

}  // namespace vpm
