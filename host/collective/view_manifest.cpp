// view_manifest (collective/view_manifest.hpp): the manifest and the base chunk; the subjects'
// chunks are in view_rows.cpp.
#include "collective/view_manifest.hpp"

#include <algorithm>
#include <cmath>

#include "collective/view_rows.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

/// The p-th quantile of the finite values of `arrays` (an evenly strided sample of at most 2^18).
double quantile(const std::vector<const std::vector<float>*>& arrays, double p) {
  size_t total = 0;
  for (const auto* a : arrays) total += a->size();
  const size_t stride = std::max<size_t>(1, total / 262144);
  std::vector<float> sample;
  for (const auto* a : arrays)
    for (size_t i = 0; i < a->size(); i += stride)
      if (std::isfinite((*a)[i])) sample.push_back((*a)[i]);
  if (sample.empty()) return 0;
  const size_t k = std::min(sample.size() - 1, static_cast<size_t>(std::lround(p * static_cast<double>(sample.size() - 1))));
  std::nth_element(sample.begin(), sample.begin() + static_cast<long>(k), sample.end());
  return sample[k];
}

void extend(double& lo, double& hi, const std::vector<float>& x) {
  for (float v : x)
    if (std::isfinite(v)) lo = std::min(lo, double(v)), hi = std::max(hi, double(v));
}

/// The feature's entry: compare options, colour ranges and the 16-bit codes of values and z.
Json feature_entry(const CohortView& v, const ViewFeature& f, FeatureCodes& codes) {
  Json j = Json::object();
  j["name"] = f.name;
  j["normalisation"] = to_string(f.normalisation);
  j["threshold"] = f.compare.threshold;
  j["fdr_q"] = f.compare.fdr_q;
  j["min_cluster"] = f.compare.min_cluster;
  j["extend"] = f.compare.extend;
  j["peak"] = f.compare.peak;
  j["test"] = to_string(f.compare.test);
  j["smoothing"] = f.smoothing;
  j["shrinkage"] = f.shrinkage;
  Json cov = Json::array();
  for (const std::string& n : f.covariates) cov.push_back(n);
  j["covariates"] = cov;
  j["image_covariate"] = f.image_covariate;
  j["sign"] = f.compare.sign;
  j["reference_subjects"] = f.reference_subjects;
  std::vector<const std::vector<float>*> normals;
  double vlo = INFINITY, vhi = -INFINITY, zlo = INFINITY, zhi = -INFINITY;
  for (const ViewSubject& s : v.subjects) {
    const auto x = s.values.find(f.name);
    if (x == s.values.end()) continue;
    extend(vlo, vhi, x->second);
    if (!s.patient) normals.push_back(&x->second);
    const auto z = s.z.find(f.name);
    if (s.patient && z != s.z.end()) extend(zlo, zhi, z->second);
  }
  codes.values[f.name] = Quantiser::over(vlo, vhi);
  codes.z[f.name] = Quantiser::over(zlo, zhi);
  Json range = Json::array(), spread = Json::array(), q = Json::object();
  range.push_back(quantile(normals, 0.02));
  range.push_back(quantile(normals, 0.98));
  spread.push_back(0.0);
  spread.push_back(quantile({&f.std}, 0.98));
  j["range"] = range;          // the value columns' colour scale: the normals' 2nd to 98th percentile
  j["spread_range"] = spread;  // the reference row's spread scale
  q["base"] = codes.values[f.name].base;
  q["step"] = codes.values[f.name].step;
  j["value_q"] = q;
  return j;
}

Json numbers(const std::vector<double>& x) {
  Json a = Json::array();
  for (double d : x) a.push_back(d);
  return a;
}

/// The base chunk: the display sphere, the reference per feature, atlas regions, the mean shape.
void base_chunk(ChunkPack& pack, const CohortView& v, const Shapes& shapes, Json& m) {
  pack.begin("base");
  std::vector<std::uint32_t> index(v.display.triangles.size());
  for (Eigen::Index f = 0; f < v.display.triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c) index[3 * f + c] = static_cast<std::uint32_t>(v.display.triangles(f, c));
  std::vector<float> sphere(v.display.vertices.size());
  for (Eigen::Index p = 0; p < v.display.vertices.rows(); ++p)
    for (int c = 0; c < 3; ++c) sphere[3 * p + c] = static_cast<float>(v.display.vertices(p, c));
  pack.add("display_index", index, "u32");
  pack.add("display_sphere", sphere, "f32");
  pack.add("display_element_triangle", std::vector<std::uint32_t>(v.display_triangle_element.begin(), v.display_triangle_element.end()), "u32");
  Json reference = Json::object();
  for (const ViewFeature& f : v.features) {
    Json r = Json::object();
    r["mean"] = pack.add("reference_mean_" + f.name, f.mean, "f32");
    r["std"] = pack.add("reference_std_" + f.name, f.std, "f32");
    std::vector<std::uint16_t> count(f.count.size());
    for (size_t e = 0; e < count.size(); ++e) count[e] = static_cast<std::uint16_t>(std::clamp(f.count[e], 0, 65535));
    r["count"] = pack.add("reference_count_" + f.name, count, "u16");
    reference[f.name] = r;
  }
  m["reference"] = reference;
  if (!v.element_label.empty()) {
    Json regions = Json::object(), names = Json::object();
    regions["buffer"] = pack.add("element_region", std::vector<std::int32_t>(v.element_label.begin(), v.element_label.end()), "i32");
    for (const auto& [id, name] : v.label_names) names[std::to_string(id)] = name;
    regions["names"] = names;
    m["regions"] = regions;
  }
  m["mean_shape"] = pack.add("mean_shape", shapes.mean, "f32");
  pack.end();
}

/// Names, shapes and options: everything of the manifest but the subjects.
Json head(const CohortView& v, const Shapes& shapes) {
  Json m = Json::object();
  m["format"] = "vpm-view-2";
  m["title"] = v.title;
  m["definition"] = to_json(v.definition);
  if (v.compared.level > v.definition.level) {  // tables finer than the page draws
    Json c = to_json(v.compared);
    c["elements"] = v.compared.elements();
    m["compared"] = c;
  }
  m["shells"] = v.definition.shells;
  m["triangles"] = v.definition.triangles();
  m["elements"] = v.definition.elements();
  Json levels = Json::array();
  for (int l : shell_levels(v.definition)) levels.push_back(l);
  m["shell_levels"] = levels;  // per shell, innermost first
  std::vector<double> offsets;
  for (long o : shell_offsets(v.definition)) offsets.push_back(static_cast<double>(o));
  m["shell_offsets"] = numbers(offsets);  // first element id of each shell, and the element count
  m["radii"] = numbers(v.mid_radii);
  m["shell_radius"] = numbers(shapes.shell_radius);
  Json d = Json::object();
  d["vertices"] = static_cast<long long>(v.display.vertices.rows());
  d["triangles"] = static_cast<long long>(v.display.triangles.rows());
  d["finer"] = v.display.triangles.rows() > v.definition.triangles();  // 4 display triangles per element triangle
  m["display"] = d;
  return m;
}

}  // namespace

std::vector<long> shell_offsets(const ElementDefinition& d) {
  std::vector<long> out{0};
  for (int l : shell_levels(d)) out.push_back(out.back() + (20L << (2 * l)));
  return out;
}

Json view_manifest(ChunkPack& pack, const CohortView& v, const ManifestOptions& o) {
  if (v.subjects.empty()) throw InputError("view page: the cohort has no subjects");
  const Shapes shapes = subject_shapes(v);
  Json m = head(v, shapes);
  FeatureCodes codes;
  Json features = Json::array();
  for (const ViewFeature& f : v.features) features.push_back(feature_entry(v, f, codes));
  m["features"] = features;
  base_chunk(pack, v, shapes, m);
  m["subjects"] = subject_chunks(pack, v, shapes, codes, o);
  if (o.columns) m["columns"] = column_chunks(pack, v, codes, o.column_elements);
  return m;
}

}  // namespace vpm::detail
