// Reading subject tables (vpm/sampling.hpp): the TSV written by write_subject_table and its sidecar.
#include <charconv>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/text.hpp"
#include "vpm/error.hpp"
#include "vpm/sampling.hpp"

namespace vpm {

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
  const Json* d = j.find("definition");
  if (!d) throw InputError(side + ": no element definition");
  t.definition = element_definition_from_json(*d, side);
  if (const Json* s = j.find("subject")) t.subject = s->string();
  if (const Json* m = j.find("mesh")) t.mesh = m->string();
  if (const Json* f = j.find("features"))
    for (size_t i = 0; i < f->size() && i < t.features.size(); ++i)
      if (const Json* src = f->at(i).find("source")) t.features[i].source = src->string();
}

}  // namespace

ElementTable read_subject_table(const std::string& path) {
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

}  // namespace vpm
