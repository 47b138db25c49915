// Subject tables (vpm/sampling.hpp): the format chosen by the file name, the metadata both
// formats carry, and the TSV export with its JSON sidecar (the HDF5 format is in
// subject_table_hdf5.cpp).
#include <charconv>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "collective/subject_table_formats.hpp"
#include "core/atomic_file.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"
#include "vpm/sampling.hpp"

namespace vpm {

TableFormat table_format(const std::string& path) {
  const std::string ext = detail::extension_of(path);
  if (ext == ".h5" || ext == ".hdf5") return TableFormat::hdf5;
  if (ext == ".tsv") return TableFormat::tsv;
  throw InputError(path + ": a subject table is .h5 (HDF5) or .tsv (text), not '" + ext + "'");
}

void write_subject_table(const std::string& path, const ElementTable& table) {
  if (table_format(path) == TableFormat::hdf5)
    detail::write_subject_table_hdf5(path, table);
  else
    detail::write_subject_table_tsv(path, table);
}

ElementTable read_subject_table(const std::string& path) { return read_subject_table(path, TableColumns{}); }

ElementTable read_subject_table(const std::string& path, const TableColumns& columns) {
  if (table_format(path) == TableFormat::hdf5) return detail::read_subject_table_hdf5(path, columns);
  ElementTable t = detail::read_subject_table_tsv(path);
  if (!columns.features.empty())
    std::erase_if(t.features, [&](const ElementFeature& f) {
      return std::find(columns.features.begin(), columns.features.end(), f.name) == columns.features.end();
    });
  if (!columns.spread)
    for (ElementFeature& f : t.features) std::vector<double>().swap(f.std);
  if (!columns.labels) t.label_images.clear();
  return t;
}

namespace detail {

Json table_metadata(const ElementTable& t) {
  Json j = Json::object();
  j["definition"] = to_json(t.definition);
  j["elements"] = t.definition.elements();
  j["subject"] = t.subject;
  j["mesh"] = t.mesh;
  Json feats = Json::array();
  for (const ElementFeature& f : t.features) {
    Json o = Json::object();
    o["name"] = f.name;
    o["source"] = f.source;
    o["interpolation"] = "trilinear";
    feats.push_back(o);
  }
  j["features"] = feats;
  Json labs = Json::array();
  for (const ElementLabels& l : t.label_images) {
    Json o = Json::object();
    o["source"] = l.source;
    o["labels"] = static_cast<long>(l.labels.size());
    labs.push_back(o);
  }
  j["label_images"] = labs;
  Json c = Json::object();
  c["samples"] = "sample points of the element (the same for every subject)";
  c["<feature>_mean"] = "mean of the image over the element's samples inside the image grid";
  c["<feature>_std"] = "population standard deviation over those samples";
  c["<feature>_count"] = "samples inside the image grid";
  c["label_<id>"] = "fraction of the element's samples on that label (nearest voxel)";
  j["columns"] = c;
  return j;
}

namespace {

bool feature_name_ok(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (char c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') return false;
  return true;
}

}  // namespace

void read_table_metadata(const Json& j, const std::string& source, ElementTable& t, bool with_features) {
  if (j.type() != Json::Type::Object) throw InputError(source + ": the metadata is not a JSON object");
  const Json* d = j.find("definition");
  if (!d) throw InputError(source + ": no element definition");
  t.definition = element_definition_from_json(*d, source);
  auto text = [&](const char* key) -> std::string {
    const Json* v = j.find(key);
    if (!v) return "";
    if (v->type() != Json::Type::String) throw InputError(source + ": '" + key + "' is not a string");
    return v->string();
  };
  t.subject = text("subject");
  t.mesh = text("mesh");
  const Json* f = j.find("features");
  if (with_features && (!f || f->type() != Json::Type::Array)) throw InputError(source + ": no list of features");
  if (!f || f->type() != Json::Type::Array) return;
  if (with_features && f->size() > 256) throw InputError(source + ": more than 256 features");
  for (size_t i = 0; i < f->size(); ++i) {
    const Json& o = f->at(i);
    const Json* src = o.type() == Json::Type::Object ? o.find("source") : nullptr;
    if (with_features) {
      const Json* name = o.type() == Json::Type::Object ? o.find("name") : nullptr;
      if (!name || name->type() != Json::Type::String || !feature_name_ok(name->string()))
        throw InputError(source + ": feature " + std::to_string(i + 1) + " has no name of letters, digits or _");
      for (const ElementFeature& g : t.features)
        if (g.name == name->string()) throw InputError(source + ": feature '" + g.name + "' is listed twice");
      ElementFeature e;
      e.name = name->string();
      t.features.push_back(std::move(e));
    }
    if (i < t.features.size() && src && src->type() == Json::Type::String) t.features[i].source = src->string();
  }
}

int checked_table_size(const std::string& path, const ElementTable& t) {
  const int n = t.definition.elements();
  const size_t un = static_cast<size_t>(n);
  for (const ElementFeature& f : t.features)
    if (f.mean.size() != un || f.count.size() != un || f.std.size() != un)
      throw InputError(path + ": feature " + f.name + " has " + std::to_string(f.mean.size()) +
                       " elements, the definition " + std::to_string(n));
  for (const ElementLabels& l : t.label_images) {
    if (l.fraction.size() != l.labels.size()) throw InputError(path + ": label fractions and labels differ in number");
    for (const auto& col : l.fraction)
      if (col.size() != un) throw InputError(path + ": a label column has " + std::to_string(col.size()) + " elements, the definition " + std::to_string(n));
  }
  return n;
}

void write_subject_table_tsv(const std::string& tsv_path, const ElementTable& t) {
  const int n = checked_table_size(tsv_path, t), triangles = t.definition.triangles();
  AtomicFile file(tsv_path);
  std::ostream& out = file.stream();
  out << "element\tshell\ttriangle\tsamples";
  for (const ElementFeature& f : t.features) out << '\t' << f.name << "_mean\t" << f.name << "_std\t" << f.name << "_count";
  for (const ElementLabels& l : t.label_images)
    for (int id : l.labels) out << "\tlabel_" << id;
  out << '\n' << std::setprecision(10);
  for (int e = 0; e < n; ++e) {
    out << e << '\t' << e / triangles << '\t' << e % triangles << '\t' << t.definition.samples;
    for (const ElementFeature& f : t.features) out << '\t' << f.mean[e] << '\t' << f.std[e] << '\t' << f.count[e];
    for (const ElementLabels& l : t.label_images)
      for (const auto& col : l.fraction) out << '\t' << col[e];
    out << '\n';
  }
  write_json_file(sidecar_path(tsv_path), table_metadata(t));
  file.commit();
}

namespace {

double number(const std::string& cell, const std::string& where) {
  double v = 0;
  const auto [p, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
  if (ec != std::errc() || p != cell.data() + cell.size()) throw InputError(where + ": '" + cell + "' is not a number");
  return v;
}

// An integral cell (element id, sample count, label) that fits an int.
int integer(const std::string& cell, const std::string& where) {
  const double v = number(cell, where);
  if (!(v >= INT_MIN && v <= INT_MAX) || v != std::floor(v)) throw InputError(where + ": '" + cell + "' is not an integer");
  return static_cast<int>(v);
}

bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() > suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Column layout from the header: the features (name_mean/_std/_count triplets) and labels.
void read_header(const std::string& path, const std::vector<std::string>& h, ElementTable& t, std::vector<int>& labels) {
  const std::vector<std::string> fixed = {"element", "shell", "triangle", "samples"};
  for (size_t i = 0; i < fixed.size(); ++i)
    if (i >= h.size() || h[i] != fixed[i]) throw InputError(path + ":1: expected column " + fixed[i] + " at position " + std::to_string(i + 1));
  size_t i = fixed.size();
  for (; i + 2 < h.size() && ends_with(h[i], "_mean"); i += 3) {
    const std::string name = h[i].substr(0, h[i].size() - 5);
    if (h[i + 1] != name + "_std" || h[i + 2] != name + "_count")
      throw InputError(path + ":1: column " + h[i] + " must be followed by " + name + "_std and " + name + "_count");
    ElementFeature f;
    f.name = name;
    t.features.push_back(f);
  }
  for (; i < h.size(); ++i) {
    if (h[i].rfind("label_", 0) != 0) throw InputError(path + ":1: unexpected column '" + h[i] + "'");
    labels.push_back(integer(h[i].substr(6), path + ":1"));
  }
}

void read_sidecar(const std::string& path, ElementTable& t) {
  const std::string side = sidecar_path(path);
  std::ifstream in(side);
  if (!in) throw InputError(side + ": cannot read the sidecar of " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  Json j;
  try {
    j = Json::parse(ss.str());
  } catch (const std::exception& e) {
    throw InputError(side + ": " + e.what());
  }
  read_table_metadata(j, side, t, false);
}

}  // namespace

ElementTable read_subject_table_tsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read");
  ElementTable t;
  std::string line;
  if (!std::getline(in, line)) throw InputError(path + ":1: empty file");
  std::vector<int> labels;
  read_header(path, detail::split_tabs(line), t, labels);
  read_sidecar(path, t);
  const int n = t.definition.elements();
  const size_t columns = 4 + 3 * t.features.size() + labels.size();
  // a row takes at least two bytes a column: refuse a sidecar's definition of more elements than
  // the file could hold before allocating for them
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  if (!ec && static_cast<double>(n) * 2.0 * static_cast<double>(columns) > static_cast<double>(bytes))
    throw InputError(path + ": its sidecar's element definition has " + std::to_string(n) + " elements, more rows than the file's " +
                     std::to_string(bytes) + " bytes could hold (truncated table, or the sidecar of another table)");
  for (ElementFeature& f : t.features) {
    f.mean.assign(n, 0);
    f.std.assign(n, 0);
    f.count.assign(n, 0);
  }
  ElementLabels lab;
  lab.labels = labels;
  lab.fraction.assign(labels.size(), std::vector<double>(n, 0.0));
  int row = 0;
  for (int ln = 2; std::getline(in, line); ++ln) {
    if (line.empty()) continue;
    const std::string where = path + ":" + std::to_string(ln);
    const std::vector<std::string> c = detail::split_tabs(line);
    if (c.size() != columns) throw InputError(where + ": " + std::to_string(c.size()) + " columns, the header has " + std::to_string(columns));
    if (row >= n) throw InputError(where + ": more rows than the " + std::to_string(n) + " elements of the definition");
    if (integer(c[0], where) != row) throw InputError(where + ": element " + c[0] + ", expected " + std::to_string(row));
    for (size_t f = 0; f < t.features.size(); ++f) {
      t.features[f].mean[row] = number(c[4 + 3 * f], where);
      t.features[f].std[row] = number(c[5 + 3 * f], where);
      t.features[f].count[row] = integer(c[6 + 3 * f], where);
    }
    for (size_t l = 0; l < labels.size(); ++l) lab.fraction[l][row] = number(c[4 + 3 * t.features.size() + l], where);
    ++row;
  }
  if (row != n) throw InputError(path + ": " + std::to_string(row) + " rows for the " + std::to_string(n) + " elements of the definition");
  if (!labels.empty()) t.label_images.push_back(std::move(lab));
  return t;
}

}  // namespace detail

}  // namespace vpm
