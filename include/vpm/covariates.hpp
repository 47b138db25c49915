#pragma once
// Subject covariates (age, sex, ...) for a normative reference (vpm/statistics.hpp): with them the
// reference's expected value at each element is a linear model of the covariates fitted over the
// normals, and a patient is compared with the value the model predicts for the patient's own
// covariates (bench/results/cohort_covariates/).
#include <map>
#include <string>
#include <vector>

#include "vpm/sampling.hpp"

namespace vpm {

/// Covariates read from a participants table (BIDS participants.tsv: a header with
/// participant_id, one row per subject, tab-separated).
struct Covariates {
  std::string source;              ///< the table's path (messages, sidecars)
  std::vector<std::string> names;  ///< the covariates asked for, e.g. {"age", "sex"}
  /// The design's columns: a numeric covariate (every value a number) is one column of its
  /// value; a categorical one (any other value) one indicator column per level after the
  /// first in sorted order, named "name=level" (e.g. "sex=M" with levels F, M).
  std::vector<std::string> columns;
  /// participant_id -> its design row (columns.size() values; NaN where the table says "n/a"
  /// or leaves the cell empty).
  std::map<std::string, std::vector<double>> rows;
};

/// Reads the covariates `names` (at least one, distinct) from the table at `path`. InputError
/// naming the file, the line and the problem: no participant_id or no such column, a row with
/// another number of cells, a repeated participant_id, a categorical covariate with more than
/// 16 levels, or a table larger than 64 MB.
Covariates read_covariates(const std::string& path, const std::vector<std::string>& names);

/// The design row of `subject` (a participant_id). InputError naming the table, the subject
/// and `what` (the element table it came from) when the table has no such row or a value is
/// missing.
std::vector<double> covariate_row(const Covariates& c, const std::string& subject, const std::string& what);

/// A reference's design over its normals: the columns, and one row per normal (same order).
struct CovariateDesign {
  std::string source;              ///< Covariates::source
  std::vector<std::string> names;  ///< Covariates::names
  std::vector<std::string> columns;
  std::vector<std::vector<double>> rows;
  bool empty() const { return columns.empty(); }
};

/// The design of `tables` (each looked up by its ElementTable::subject; `names` name the tables
/// in messages).
CovariateDesign covariate_design(const Covariates& c, const std::vector<ElementTable>& tables,
                                 const std::vector<std::string>& names);

}  // namespace vpm
