// Reference sums in HDF5 (vpm/reference_sums.hpp: write_reference_sums, read_reference_sums).
#include <cmath>
#include <set>

#include "io/hdf5.hpp"
#include "vpm/error.hpp"
#include "vpm/reference_sums.hpp"

namespace vpm {

namespace h5 = detail::h5;

namespace {

constexpr const char* kFormat = "vpm reference sums";
constexpr std::int64_t kFormatVersion = 1;
constexpr std::size_t kMaxNamesBytes = std::size_t{256} << 20;
constexpr double kMaxValues = double(std::size_t{1} << 28);

Json string_array(const std::vector<std::string>& v) {
  Json a = Json::array();
  for (const std::string& s : v) a.push_back(s);
  return a;
}

// The strings of JSON array `j` (InputError naming `where` otherwise).
std::vector<std::string> strings(const Json* j, const std::string& where) {
  if (!j || j->type() != Json::Type::Array) throw InputError(where + ": not a list of strings");
  std::vector<std::string> out;
  for (size_t i = 0; i < j->size(); ++i) {
    if (j->at(i).type() != Json::Type::String) throw InputError(where + ": item " + std::to_string(i + 1) + " is not a string");
    out.push_back(j->at(i).string());
  }
  return out;
}

std::string text_of(const Json& j, const char* key, const std::string& where) {
  const Json* v = j.find(key);
  if (!v || v->type() != Json::Type::String) throw InputError(where + ": '" + key + "' is missing or not a string");
  return v->string();
}

ReferenceRecipe recipe_from_json(const Json* j, const std::string& where) {
  if (!j || j->type() != Json::Type::Object) throw InputError(where + ": no recipe");
  ReferenceRecipe r;
  r.feature = text_of(*j, "feature", where);
  r.normalisation = parse_normalisation(text_of(*j, "normalisation", where));
  const Json* s = j->find("smoothing");
  if (!s || s->type() != Json::Type::Number || !(s->number() >= 0 && s->number() <= 8) || s->number() != std::floor(s->number()))
    throw InputError(where + ": 'smoothing' is not an integer in 0..8");
  r.smoothing = static_cast<int>(s->number());
  r.image_covariate = text_of(*j, "image_covariate", where);
  r.covariates = strings(j->find("covariates"), where + ": covariates");
  r.covariate_columns = strings(j->find("covariate_columns"), where + ": covariate_columns");
  r.covariate_table = text_of(*j, "covariate_table", where);
  return r;
}

std::int64_t number_of(const Json& j, const char* key, const std::string& where) {
  const Json* v = j.find(key);
  if (!v || v->type() != Json::Type::Number || v->number() != std::floor(v->number()) || v->number() < 0 || v->number() > 1e12)
    throw InputError(where + ": '" + key + "' is missing or not a count");
  return static_cast<std::int64_t>(v->number());
}

}  // namespace

void write_reference_sums(const std::string& path, const ReferenceSums& sums) {
  Json meta = Json::object();
  meta["definition"] = to_json(sums.definition());
  meta["elements"] = sums.definition().elements();
  meta["recipe"] = to_json(sums.recipe());
  meta["model_columns"] = sums.model_columns();
  meta["stride"] = sums.stride();
  meta["normals"] = static_cast<long>(sums.normals().size());
  meta["layout"] = "per element: the packed upper triangle of sum x x^T (x = 1, covariates, image covariate), "
                   "then sum x y, then sum y^2, over the normals with data there";
  h5::Writer w(path);
  w.attribute("/", "format", std::string(kFormat));
  w.attribute("/", "format_version", kFormatVersion);
  w.attribute("/", "metadata", meta.dump(-1));
  w.attribute("/", "feature", sums.recipe().feature);
  w.group("/normals");
  w.text("/normals/names", string_array(sums.normals()).dump(-1));
  const size_t p = sums.recipe().covariate_columns.size(), N = sums.normals().size();
  if (p > 0) {
    std::vector<double> design(N * p);
    for (size_t i = 0; i < N; ++i)
      for (size_t j = 0; j < p; ++j) design[i * p + j] = sums.design()[i][j];
    w.dataset("/normals/design", design.data(), N, p, h5::Stored::f64);
  }
  const size_t n = static_cast<size_t>(sums.definition().elements());
  w.dataset("/sums", sums.element(0), n, static_cast<size_t>(sums.stride()), h5::Stored::f64, false);
  w.commit();
}

ReferenceSums read_reference_sums(const std::string& path) {
  const h5::Reader r(path);
  if (r.string_attribute("/", "format", 256) != kFormat)
    throw InputError(path + ": not vpm reference sums (no root attribute format = '" + kFormat + "')");
  const std::optional<std::int64_t> version = r.integer_attribute("/", "format_version");
  if (version != kFormatVersion)
    throw InputError(path + ": reference sums format version " + (version ? std::to_string(*version) : "missing") +
                     ", this vpm reads " + std::to_string(kFormatVersion));
  const std::string where = path + ": metadata";
  Json meta;
  try {
    meta = Json::parse(r.string_attribute("/", "metadata").value_or(""));
  } catch (const std::exception& e) {
    throw InputError(where + ": " + e.what());
  }
  if (meta.type() != Json::Type::Object || !meta.find("definition")) throw InputError(where + ": no element definition");
  const ElementDefinition definition = element_definition_from_json(*meta.find("definition"), where);
  ReferenceSums sums(definition, recipe_from_json(meta.find("recipe"), where + ": recipe"));
  if (number_of(meta, "stride", where) != sums.stride_ || number_of(meta, "model_columns", where) != sums.q_)
    throw InputError(where + ": stride and model columns do not match the recipe");
  const size_t N = static_cast<size_t>(number_of(meta, "normals", where));
  Json names;
  try {
    names = Json::parse(r.text("/normals/names", kMaxNamesBytes));
  } catch (const InputError&) {
    throw;
  } catch (const std::exception& e) {
    throw InputError(path + ": /normals/names: " + e.what());
  }
  sums.names_ = strings(&names, path + ": /normals/names");
  if (sums.names_.size() != N) throw InputError(path + ": /normals/names: " + std::to_string(sums.names_.size()) + " names for " + std::to_string(N) + " normals");
  if (std::set<std::string>(sums.names_.begin(), sums.names_.end()).size() != N)
    throw InputError(path + ": /normals/names: a normal is named twice");
  const size_t p = sums.recipe_.covariate_columns.size();
  sums.design_.assign(N, std::vector<double>(p));
  if (p > 0) {
    const std::vector<double> design = r.doubles("/normals/design", N, p);
    for (size_t i = 0; i < N; ++i)
      for (size_t j = 0; j < p; ++j) {
        sums.design_[i][j] = design[i * p + j];
        if (!std::isfinite(design[i * p + j])) throw InputError(path + ": /normals/design: a value is not finite");
      }
  }
  const size_t n = static_cast<size_t>(definition.elements()), stride = static_cast<size_t>(sums.stride_);
  if (double(n) * double(stride) > kMaxValues) throw InputError(path + ": /sums: more values than a reference can hold");
  sums.sums_ = r.doubles("/sums", n, stride);
  for (size_t e = 0; e < n; ++e) {
    const double* s = sums.sums_.data() + e * stride;
    for (size_t k = 0; k < stride; ++k)
      if (!std::isfinite(s[k])) throw InputError(path + ": /sums: element " + std::to_string(e) + " holds a value that is not finite");
    if (s[0] < 0 || s[0] > double(N) || s[0] != std::floor(s[0]))
      throw InputError(path + ": /sums: element " + std::to_string(e) + " counts " + std::to_string(s[0]) + " normals of " + std::to_string(N));
  }
  return sums;
}

}  // namespace vpm
