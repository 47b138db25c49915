// load_cohort_view (vpm/cohort_view.hpp): a cohort read back from the workflow's results folder.
#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <optional>

#include "collective/cohort_view_detail.hpp"
#include "collective/view_coarsen.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/label_names.hpp"
#include "vpm/reference_sums.hpp"

namespace vpm {

namespace fs = std::filesystem;

namespace {

/// One `vpm compare` result: its sidecar, the patient's and the normals' tables.
struct ComparisonFile {
  std::string tsv, feature, patient_table;
  std::vector<std::string> normal_tables;
  Normalisation normalisation = Normalisation::proportional;
  int smoothing = 0;
  double shrinkage = 0;
  std::string covariate_table;               ///< the participants table (empty: no covariates)
  std::vector<std::string> covariate_names;
  std::string image_covariate;               ///< Reference::image_covariate (empty: none)
  CompareOptions options;
  size_t clusters = 0;
};

/// `path` as written, or relative to the folder holding the results folder: a file (names too
/// long for the file system, folders and devices such as /dev/zero are not found).
std::string resolve(const std::string& path, const fs::path& results, const std::string& what) {
  std::error_code ec;
  if (fs::is_regular_file(path, ec)) return path;
  const fs::path alt = results.parent_path() / path;
  if (fs::is_regular_file(alt, ec)) return alt.string();
  throw InputError(path + ": " + what + " not found");
}

/// json[key], or InputError naming the sidecar and the key.
const Json& need(const Json& json, const char* key, const std::string& side) {
  const Json* j = json.find(key);
  if (!j || j->type() == Json::Type::Null) throw InputError(side + ": no '" + key + "'");
  return *j;
}

/// An integral number (json[key] when present, else `fallback`), or InputError naming the sidecar and the key.
int integer(const Json& json, const char* key, const std::string& side, std::optional<int> fallback = {}) {
  const Json* j = json.find(key);
  if (!j && fallback) return *fallback;
  const double x = need(json, key, side).number();
  if (!(x >= INT_MIN && x <= INT_MAX) || x != std::floor(x)) throw InputError(side + ": '" + key + "' is not an integer");
  return static_cast<int>(x);
}

/// reference.covariates {table, names} of a sidecar into c (absent: none).
void read_covariate_names(const Json& ref, const fs::path& results, const std::string& side, ComparisonFile& c) {
  const Json* cov = ref.find("covariates");
  if (!cov) return;
  const Json& table = need(*cov, "table", side);
  const Json& names = need(*cov, "names", side);
  if (table.type() != Json::Type::String || names.type() != Json::Type::Array || names.size() == 0)
    throw InputError(side + ": 'covariates' needs a table path and a list of names");
  c.covariate_table = resolve(table.string(), results, "the participants table named in " + side);
  for (size_t i = 0; i < names.size(); ++i) {
    if (names.at(i).type() != Json::Type::String) throw InputError(side + ": a covariate name is not a string");
    c.covariate_names.push_back(names.at(i).string());
  }
}

std::vector<ComparisonFile> read_comparisons(const fs::path& results, const std::string& only) {
  const fs::path dir = results / "compare";
  if (!fs::is_directory(dir)) throw InputError(dir.string() + ": no such folder; run the workflow's group level (vpm compare) first");
  std::vector<ComparisonFile> out;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".json") continue;
    const std::string side = entry.path().string();
    const Json j = read_json_file(side);
    const Json *ref = j.find("reference"), *pat = j.find("patient"), *opt = j.find("options"), *res = j.find("result");
    if (!ref || !pat || !opt || !res) continue;  // not a comparison's sidecar
    ComparisonFile c;
    c.tsv = (entry.path().parent_path() / entry.path().stem()).string() + ".tsv";
    c.feature = ref->find("feature") ? ref->find("feature")->string() : "";
    if (!only.empty() && c.feature != only) continue;
    c.patient_table = resolve(pat->string(), results, "the patient's table named in " + side);
    const Json* tables = ref->find("tables");
    if (!tables || c.feature.empty()) throw InputError(side + ": no reference feature or tables");
    for (size_t i = 0; i < tables->size(); ++i)
      c.normal_tables.push_back(resolve(tables->at(i).string(), results, "a normal's table named in " + side));
    c.normalisation = parse_normalisation(need(*ref, "normalisation", side).string());
    c.smoothing = integer(*ref, "smoothing", side, 0);
    if (const Json* sh = ref->find("shrinkage")) c.shrinkage = sh->number();  // absent before 2026-11-28
    read_covariate_names(*ref, results, side, c);
    if (const Json* image = ref->find("image_covariate")) {  // absent before 2026-11-29: none
      if (image->type() != Json::Type::String) throw InputError(side + ": 'image_covariate' is not a string");
      c.image_covariate = image->string();
    }
    c.options.threshold = need(*opt, "threshold", side).number();
    c.options.fdr_q = need(*opt, "fdr_q", side).number();
    c.options.min_cluster = integer(*opt, "min_cluster", side);
    c.options.sign = integer(*opt, "sign", side);
    if (const Json* extend = opt->find("extend")) c.options.extend = extend->number();  // absent before 2026-11-26
    if (const Json* peak = opt->find("peak")) c.options.peak = peak->number();        // absent before 2026-11-25
    if (const Json* rel = opt->find("relative_extent")) c.options.relative_extent = rel->number();  // absent before 2026-11-28
    if (const Json* tfce = opt->find("tfce_level")) c.options.tfce_level = tfce->number();  // absent: clusters
    if (const Json* test = opt->find("test")) c.options.test = parse_single_case_test(test->string());
    if (const auto bad = compare_option_error(c.options))
      throw InputError(side + ": options." + bad->field + ": " + bad->problem);
    c.clusters = res->find("clusters") ? res->find("clusters")->size() : 0;
    out.push_back(std::move(c));
  }
  if (out.empty())
    throw InputError(dir.string() + ": no comparison" + (only.empty() ? "" : " of feature '" + only + "'") +
                     " (sidecars of vpm compare); run the workflow's group level first");
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.tsv < b.tsv; });
  return out;
}

/// Subject tables by path, without their element values: what the page still needs of them (the
/// definition, the subject, the registered mesh, the features' images). The values are read a
/// table at a time where they are used, so memory does not grow with the cohort's tables.
struct Tables {
  std::map<std::string, ElementTable> by_path;
  /// `t` (read from `path`) kept without its values.
  const ElementTable& keep(const std::string& path, ElementTable t) {
    for (ElementFeature& f : t.features) std::vector<double>().swap(f.mean), std::vector<double>().swap(f.std), std::vector<int>().swap(f.count);
    t.label_images.clear();
    return by_path.insert_or_assign(path, std::move(t)).first->second;
  }
  /// The table at `path` as kept, or its metadata alone (no features), read once.
  const ElementTable& meta(const std::string& path) {
    if (auto it = by_path.find(path); it != by_path.end()) return it->second;
    TableColumns columns;
    columns.features = {""};  // no feature has an empty name
    columns.spread = columns.labels = false;
    return keep(path, read_subject_table(path, columns));
  }
};

std::string subject_id(const ElementTable& t, const std::string& path) {
  return t.subject.empty() ? fs::path(path).stem().string() : t.subject;
}

ViewSubject& subject_for(CohortView& v, std::map<std::string, size_t>& index, const std::string& id, bool patient) {
  auto it = index.find(id);
  if (it == index.end()) {
    it = index.emplace(id, v.subjects.size()).first;
    v.subjects.push_back({});
    v.subjects.back().id = id;
  }
  ViewSubject& s = v.subjects[it->second];
  s.patient = s.patient || patient;
  return s;
}

std::vector<float> to_float(const std::vector<double>& x) { return {x.begin(), x.end()}; }

}  // namespace

std::vector<std::vector<double>> leave_one_out_z(const std::vector<std::vector<double>>& x) {
  const size_t n = x.size(), m = n ? x[0].size() : 0;
  std::vector<std::vector<double>> z(n, std::vector<double>(m, std::nan("")));
  for (size_t e = 0; e < m; ++e) {
    double sum = 0, sq = 0;
    int count = 0;
    for (size_t i = 0; i < n; ++i)
      if (std::isfinite(x[i][e])) sum += x[i][e], sq += x[i][e] * x[i][e], ++count;
    for (size_t i = 0; i < n && count >= 4; ++i) {
      if (!std::isfinite(x[i][e])) continue;
      const double k = count - 1, mean = (sum - x[i][e]) / k;
      const double var = (sq - x[i][e] * x[i][e] - k * mean * mean) / (k - 1);
      if (var > 0) z[i][e] = (x[i][e] - mean) / std::sqrt(var);
    }
  }
  return z;
}

namespace {

/// The reference of one feature, built in one streaming pass over the normals' tables (each
/// normal's display values kept as it is read), every subject's values and the patients'
/// z-scores against it, all carried to the display elements by `to`.
void add_feature(CohortView& v, const CanonicalElements& el, const detail::ElementCoarsening& to,
                 const std::vector<const ComparisonFile*>& comps, Tables& tables, std::map<std::string, size_t>& index) {
  const ComparisonFile& first = *comps.front();
  if (first.normal_tables.size() < 3)
    throw InputError(first.tsv + ": its reference names " + std::to_string(first.normal_tables.size()) + " normals, at least 3 are needed");
  if (!(first.shrinkage >= 0 && first.shrinkage <= 1))
    throw InputError(first.tsv + ": shrinkage " + std::to_string(first.shrinkage) + " is not in [0, 1]");
  std::optional<Covariates> cov;
  if (!first.covariate_names.empty()) cov = read_covariates(first.covariate_table, first.covariate_names);
  const ReferenceRecipe recipe =
      reference_recipe(first.feature, first.normalisation, first.smoothing, first.image_covariate, cov ? &*cov : nullptr);
  NormalSource source = table_files(first.normal_tables, v.compared, recipe, &el, cov ? &*cov : nullptr);
  std::vector<std::vector<float>> shown(first.normal_tables.size());
  std::vector<std::string> ids(first.normal_tables.size());
  source.values = [&, read = source.values](size_t i) {  // called from several threads, each i once
    NormalValues nv = read(i);
    shown[i] = to.mean(to_float(nv.feature));
    ids[i] = nv.subject.empty() ? fs::path(first.normal_tables[i]).stem().string() : nv.subject;
    return nv;
  };
  const Reference ref = sum_normals(v.compared, recipe, source).reference(&el, first.shrinkage);
  v.features.push_back({first.feature, first.normalisation, first.smoothing, first.shrinkage, first.covariate_names,
                        first.image_covariate, first.options, ref.subjects, to.mean(to_float(ref.mean)),
                        to.rms(to_float(ref.std)), to.least(ref.count)});
  for (size_t i = 0; i < shown.size(); ++i) {
    subject_for(v, index, ids[i], false).values[first.feature] = std::move(shown[i]);
    tables.meta(first.normal_tables[i]);
  }
  for (const ComparisonFile* c : comps) {
    if (c->normal_tables != first.normal_tables || c->normalisation != first.normalisation ||
        c->smoothing != first.smoothing || c->shrinkage != first.shrinkage ||
        c->covariate_names != first.covariate_names || c->covariate_table != first.covariate_table ||
        c->image_covariate != first.image_covariate)
      throw InputError(c->tsv + ": compared against other normals than " + first.tsv + "; one reference per feature");
    ElementTable t = read_subject_table(c->patient_table);
    if (t.definition != v.compared)
      throw InputError(c->patient_table + ": element definition differs from " + comps.front()->patient_table + "'s");
    const Comparison cmp =
        compare_to_reference(el, ref, t, c->options, cov ? covariate_row(*cov, t.subject, c->patient_table) : std::vector<double>{});
    if (cmp.clusters.size() != c->clusters)
      throw InputError(c->tsv + ": its " + std::to_string(c->clusters) + " foci differ from the " +
                       std::to_string(cmp.clusters.size()) + " its tables give now; rerun vpm compare");
    ViewSubject& s = subject_for(v, index, subject_id(t, c->patient_table), true);
    s.values[c->feature] = to.mean(to_float(cmp.patient));
    s.z[c->feature] = to.mean(to_float(cmp.z));
    s.foci_count[c->feature] = static_cast<int>(cmp.clusters.size());
    s.cluster[c->feature] = to.most_frequent(std::vector<std::int32_t>(cmp.cluster.begin(), cmp.cluster.end()));
    const std::string base = c->tsv.substr(0, c->tsv.size() - 4);
    if (fs::exists(base + "_foci.tsv")) {
      std::vector<ViewFocus> foci = detail::read_view_foci(base + "_foci.tsv", cmp);
      for (ViewFocus& f : foci) f.peak_element = f.peak_element >= 0 ? to.of(f.peak_element) : -1;
      s.foci[c->feature] = std::move(foci);
    }
    tables.keep(c->patient_table, std::move(t));
  }
}

/// Shapes (every subject) and, for patients, element centres and slices.
void add_geometry(CohortView& v, const CanonicalElements& el, Tables& tables, const std::vector<ComparisonFile>& comps,
                  const fs::path& results, const CohortViewOptions& opt) {
  std::map<std::string, std::string> mesh_of;
  std::map<std::string, std::map<std::string, std::pair<std::string, std::string>>> slices_of;  // id -> feature -> image, z
  for (const auto& [path, t] : tables.by_path) mesh_of[subject_id(t, path)] = resolve(t.mesh, results, "the registered mesh named in " + path);
  for (const ComparisonFile& c : comps) {
    const ElementTable& t = tables.meta(c.patient_table);
    const std::string id = subject_id(t, c.patient_table), z = c.tsv.substr(0, c.tsv.size() - 4) + "_z.nii.gz";
    for (const ElementFeature& f : t.features)
      if (std::error_code ec; f.name == c.feature && fs::is_regular_file(f.source, ec) && fs::exists(z, ec))
        slices_of[id][c.feature] = {f.source, z};
  }
  for (ViewSubject& s : v.subjects) {
    const TetMesh reg = read_mesh(mesh_of.at(s.id));
    s.native = native_shell_surfaces(el, v.display, reg);
    if (!s.patient) continue;
    s.centres = native_element_centres(el, reg);
    for (const auto& [feature, files] : slices_of[s.id])
      s.slices[feature] = detail::read_view_slices(files.first, files.second, opt.max_slice_voxels);
  }
}

}  // namespace

CohortView load_cohort_view(const std::string& results_dir, const CohortViewOptions& opt) {
  if (opt.max_display_level < 0) throw InputError("view: the display level " + std::to_string(opt.max_display_level) + " is negative");
  const fs::path results = fs::absolute(results_dir).lexically_normal();
  const std::vector<ComparisonFile> comps = read_comparisons(results, opt.feature);
  Tables tables;
  CohortView v;
  v.title = opt.title.empty() ? "vpm cohort: " + results.parent_path().filename().string() : opt.title;
  v.compared = tables.meta(comps.front().patient_table).definition;
  v.definition = detail::display_definition(v.compared, opt.max_display_level);
  const CanonicalElements el(v.compared), shown(v.definition);
  v.mid_radii = shell_mid_radii(shown);
  // one level finer than the elements' for smooth shading, up to level 4 (2,562 vertices per shell
  // and subject: at level 5 the page of a 60-subject cohort with 19 graded shells held 70 MB of them)
  v.display = icosphere(v.definition.level < 4 ? v.definition.level + 1 : v.definition.level);
  v.display_triangle_element = display_triangle_elements(shown, v.display);
  const detail::ElementCoarsening to(el, shown);
  std::map<std::string, size_t> index;
  std::vector<std::string> order;
  for (const ComparisonFile& c : comps)
    if (std::find(order.begin(), order.end(), c.feature) == order.end()) order.push_back(c.feature);
  for (const std::string& f : order) {
    std::vector<const ComparisonFile*> of;
    for (const ComparisonFile& c : comps)
      if (c.feature == f) of.push_back(&c);
    add_feature(v, el, to, of, tables, index);
  }
  for (const auto& [path, t] : tables.by_path)
    if (t.definition != v.compared)
      throw InputError(path + ": element definition differs from " + comps.front().patient_table + "'s");
  add_geometry(v, shown, tables, comps, results, opt);
  std::stable_sort(v.subjects.begin(), v.subjects.end(), [](const ViewSubject& a, const ViewSubject& b) {
    return a.patient != b.patient ? a.patient : a.id < b.id;
  });
  const std::string templ = !opt.template_mesh.empty() ? opt.template_mesh : (results / "template" / "template_ball.vtu").string();
  if (!opt.template_mesh.empty() || fs::exists(templ)) v.element_label = detail::element_labels(shown, templ);
  if (!opt.label_names.empty()) v.label_names = read_label_names(opt.label_names);
  return v;
}

}  // namespace vpm
