// Covariates from a participants table (vpm/covariates.hpp).
#include "vpm/covariates.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <set>

#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm {

namespace {

constexpr std::uintmax_t kMaxTableBytes = 64u << 20;
constexpr size_t kMaxLevels = 16;
const double kMissing = std::numeric_limits<double>::quiet_NaN();

bool missing(const std::string& cell) { return cell.empty() || cell == "n/a" || cell == "NA"; }

bool parse_number(const std::string& cell, double& v) {
  const auto [p, ec] = std::from_chars(cell.data(), cell.data() + cell.size(), v);
  return ec == std::errc() && p == cell.data() + cell.size() && std::isfinite(v);
}

// The table's rows as cells, the header first, with the line number of each in the file (blank
// lines skipped); checks size and shape.
struct Rows {
  std::vector<std::vector<std::string>> cells;
  std::vector<int> lines;
};

Rows read_rows(const std::string& path) {
  std::error_code ec;
  const auto bytes = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(path + ": cannot read the participants table");
  if (bytes > kMaxTableBytes) throw InputError(path + ": larger than 64 MB; not a participants table");
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot read the participants table");
  Rows table;
  auto& rows = table.cells;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (line.empty() || line == "\r") continue;  // blank lines
    rows.push_back(detail::split_tabs(line));
    table.lines.push_back(number);
    if (rows.size() > 1 && rows.back().size() != rows[0].size())
      throw InputError(path + ":" + std::to_string(number) + ": " + std::to_string(rows.back().size()) +
                       " cells where the header has " + std::to_string(rows[0].size()));
  }
  if (rows.empty()) throw InputError(path + ": empty participants table");
  return table;
}

size_t column_of(const std::vector<std::string>& header, const std::string& name, const std::string& path) {
  const auto it = std::find(header.begin(), header.end(), name);
  if (it == header.end()) throw InputError(path + ":1: no column '" + name + "'");
  return static_cast<size_t>(it - header.begin());
}

// One covariate's design columns: its value, or indicators of the levels after the first.
struct Coding {
  bool numeric = true;
  std::vector<std::string> levels;  // categorical: sorted
};

Coding coding_of(const std::vector<std::vector<std::string>>& rows, size_t col, const std::string& name,
                 const std::string& path) {
  Coding c;
  std::set<std::string> levels;
  for (size_t r = 1; r < rows.size(); ++r) {
    const std::string& cell = rows[r][col];
    if (missing(cell)) continue;
    double v = 0;
    if (!parse_number(cell, v)) c.numeric = false;
    levels.insert(cell);
  }
  if (c.numeric) return c;
  if (levels.size() > kMaxLevels)
    throw InputError(path + ": covariate '" + name + "' has " + std::to_string(levels.size()) + " levels (at most " +
                     std::to_string(kMaxLevels) + "); is it a number column with a stray text value?");
  if (levels.size() < 2)
    throw InputError(path + ": covariate '" + name + "' has the one value '" + *levels.begin() +
                     "' in the whole table: nothing to adjust for");
  c.levels.assign(levels.begin(), levels.end());
  return c;
}

}  // namespace

Covariates read_covariates(const std::string& path, const std::vector<std::string>& names) {
  if (names.empty()) throw InputError(path + ": no covariates asked for");
  for (size_t i = 0; i < names.size(); ++i)
    if (std::find(names.begin(), names.begin() + static_cast<long>(i), names[i]) != names.begin() + static_cast<long>(i))
      throw InputError("covariate '" + names[i] + "' asked for twice");
  const Rows table = read_rows(path);
  const auto& rows = table.cells;
  Covariates c;
  c.source = path;
  c.names = names;
  const size_t id = column_of(rows[0], "participant_id", path);
  std::vector<size_t> cols;
  std::vector<Coding> codings;
  for (const std::string& name : names) {
    cols.push_back(column_of(rows[0], name, path));
    codings.push_back(coding_of(rows, cols.back(), name, path));
    if (codings.back().numeric) {
      c.columns.push_back(name);
    } else {
      for (size_t l = 1; l < codings.back().levels.size(); ++l) c.columns.push_back(name + "=" + codings.back().levels[l]);
    }
  }
  for (size_t r = 1; r < rows.size(); ++r) {
    const std::string& subject = rows[r][id];
    std::vector<double> row;
    for (size_t k = 0; k < names.size(); ++k) {
      const std::string& cell = rows[r][cols[k]];
      const Coding& cd = codings[k];
      double v = 0;
      if (cd.numeric) {
        row.push_back(missing(cell) || !parse_number(cell, v) ? kMissing : v);
        continue;
      }
      for (size_t l = 1; l < cd.levels.size(); ++l) row.push_back(missing(cell) ? kMissing : double(cell == cd.levels[l]));
    }
    if (!c.rows.emplace(subject, std::move(row)).second)
      throw InputError(path + ":" + std::to_string(table.lines[r]) + ": participant_id '" + subject + "' repeated");
  }
  return c;
}

std::vector<double> covariate_row(const Covariates& c, const std::string& subject, const std::string& what) {
  const auto it = c.rows.find(subject);
  if (it == c.rows.end())
    throw InputError(c.source + ": no row for participant '" + subject + "' (the subject of " + what + ")");
  for (size_t k = 0; k < it->second.size(); ++k)
    if (std::isnan(it->second[k]))
      throw InputError(c.source + ": participant '" + subject + "' has no value for " + c.columns[k] + " (the subject of " +
                       what + ")");
  return it->second;
}

CovariateDesign covariate_design(const Covariates& c, const std::vector<ElementTable>& tables,
                                 const std::vector<std::string>& names) {
  CovariateDesign d;
  d.source = c.source;
  d.names = c.names;
  d.columns = c.columns;
  for (size_t i = 0; i < tables.size(); ++i) d.rows.push_back(covariate_row(c, tables[i].subject, names[i]));
  return d;
}

}  // namespace vpm
