#pragma once
// Cohort statistics over the canonical elements (paper 6.2; docs/collective.md): a reference
// from the normals' subject tables (vpm/sampling.hpp), a patient's per-element z-scores, and
// foci: elements beyond a threshold in clusters of adjacent elements.
#include <optional>
#include <string>
#include <vector>

#include "vpm/covariates.hpp"
#include "vpm/elements.hpp"
#include "vpm/json.hpp"
#include "vpm/sampling.hpp"

namespace vpm {

/// Subject-wise intensity normalisation before comparing subjects.
enum class Normalisation {
  none,          ///< the feature as sampled
  proportional,  ///< divided by the subject's global mean (count-weighted mean over elements), as PET analyses do
};
/// "none", "proportional"; InputError otherwise.
Normalisation parse_normalisation(const std::string& name);
const char* to_string(Normalisation n);

/// The feature `name` of `table`, normalised; elements without samples are NaN. InputError when
/// the table has no such feature.
std::vector<double> normalised_feature(const ElementTable& table, const std::string& name, Normalisation n);

/// `values` (one per element; NaN: no data) averaged over each element's neighbourhood: the
/// elements within `rings` steps of face adjacency (CanonicalElements::neighbours), weighted by
/// volume, NaNs skipped. rings = 0 returns `values`.
std::vector<double> smooth_over_elements(const CanonicalElements& elements, const std::vector<double>& values, int rings);

/// How a patient's element value is compared with the normals' sample there.
enum class SingleCaseTest {
  z,               ///< z = (x - mean) / std, the normals' mean and std taken as exact
  /// Crawford & Howell (1998): t = (x - mean) / (std sqrt((n + 1) / n)) with n - 1 degrees of
  /// freedom (n: the normals with data at the element), reported as the z with the same tail
  /// probability, so that thresholds, FDR and the view stay in z units. With few normals the
  /// estimated mean and spread are uncertain and this z is smaller than the plain one (n = 20:
  /// plain 3 -> 2.73; n = 50: 2.89).
  crawford_howell,
};
/// "z", "crawford-howell"; InputError otherwise.
SingleCaseTest parse_single_case_test(const std::string& name);
const char* to_string(SingleCaseTest t);

/// Per-element reference statistics over the normals.
struct Reference {
  ElementDefinition definition;
  std::string feature;
  Normalisation normalisation = Normalisation::proportional;
  int smoothing = 0;  ///< rings of smooth_over_elements applied to every subject's normalised feature
  /// Variance shrinkage across adjacent elements, in [0, 1]: each element's variance is
  /// (1 - shrinkage) s_e^2 + shrinkage * (the mean of s^2 over e and its adjacent elements), a
  /// spread that few normals estimate more steadily (bench/results/cohort_shrink/).
  double shrinkage = 0;
  int subjects = 0;
  std::vector<double> mean, std;  ///< per element (sample standard deviation, n - 1); NaN without data
  std::vector<int> count;         ///< per element: the normals with data there
  /// The design's columns when the reference models covariates (vpm/covariates.hpp; empty:
  /// none). Then, per element, `mean` is the model's value at the normals' mean covariates and
  /// `std` the residual spread (n - p - 1 degrees of freedom, p = covariates.size(); shrunk as
  /// above), and an element needs more than p + 1 normals with data.
  std::vector<std::string> covariates;
  std::string covariate_table;                ///< CovariateDesign::source
  std::vector<std::string> covariate_names;   ///< CovariateDesign::names
  std::vector<double> covariate_centre;  ///< the normals' mean design row (the model is centred there)
  /// A second feature of the tables (e.g. "t1w") as a covariate that varies by element (empty:
  /// none): each element's model gains the normals' own value of that feature there (normalised
  /// and smoothed as `feature`), so that what the structure explains (a residual misalignment
  /// of grey matter, partial volumes) is not read as a loss of function; the patient is compared
  /// with the value its own structure predicts (bench/results/cohort_image_covariate/).
  std::string image_covariate;
  std::vector<double> image_covariate_centre;  ///< per element: the normals' mean of image_covariate
  /// per element q = p + 1 (+ 1 with an image covariate): the value at the centre, then the
  /// slopes (the image covariate's last)
  std::vector<double> coefficients;
  /// per element q^2, row-major: (X^T X)^-1 of the centred design of the normals with data
  /// there (a patient's leverage)
  std::vector<double> gram_inverse;
  /// the model's columns per element: 1 + covariates.size() + (image_covariate empty ? 0 : 1)
  int model_columns() const { return 1 + static_cast<int>(covariates.size()) + (image_covariate.empty() ? 0 : 1); }
  bool has_model() const { return model_columns() > 1; }
};

/// The reference of `normals` (at least 3). `names` (same length) name the tables in messages.
/// InputError when the element definitions differ or a table lacks the feature.
Reference build_reference(const std::vector<ElementTable>& normals, const std::vector<std::string>& names,
                          const std::string& feature, Normalisation normalisation);
/// As above, every normal's normalised feature first smoothed over `smoothing` rings of
/// `elements` (which must have the tables' definition; compare_to_reference then smooths the
/// patient's the same way), and the spread shrunk across adjacent elements by `shrinkage`
/// (Reference::shrinkage; InputError outside [0, 1]).
/// With a non-empty `covariates` design (one row per normal, vpm/covariates.hpp) the mean is a
/// linear model of the covariates (Reference::covariates); InputError when they do not vary
/// independently over the normals. A non-empty `image_covariate` (a feature of the tables other
/// than `feature`) adds that feature per element to the model (Reference::image_covariate);
/// InputError when it is `feature` itself or a table lacks it.
Reference build_reference(const CanonicalElements& elements, const std::vector<ElementTable>& normals,
                          const std::vector<std::string>& names, const std::string& feature, Normalisation normalisation,
                          int smoothing, double shrinkage = 0, const CovariateDesign& covariates = {},
                          const std::string& image_covariate = {});

struct CompareOptions {
  double threshold = 3.0;  ///< |z| beyond which an element is a candidate (ignored with fdr_q > 0)
  double fdr_q = 0;        ///< > 0: Benjamini-Hochberg threshold at this false discovery rate instead
  int min_cluster = 3;     ///< foci: clusters of at least this many adjacent candidate elements
  /// > 0: hysteresis: a focus grows from its candidates into the adjacent elements with
  /// |z| >= extend (< the threshold), and needs min_cluster candidates among its elements
  double extend = 0;
  /// In (0, 1]: each focus is redrawn over its elements whose local mean of |z| (over the
  /// element and its adjacent elements, which keeps z's unit noise from jittering the edge
  /// outwards) reaches this fraction of the largest such mean in the focus, connected through
  /// such elements to its peak: an extent that follows the focus's own amplitude, where the
  /// hysteresis' fixed |z| level draws a strong focus too large (a blurred ball of peak z 10 at
  /// 1.45x its volume). Only trims: every element stays at or above the hysteresis level, and
  /// which foci are found (and their candidates) does not change. A blurred ball's edge lies at
  /// 0.38-0.49 of its peak; 0.3 drew the best Dice on the synthetic cohorts
  /// (bench/results/cohort_relative_extent/). 0: off.
  double relative_extent = 0;
  /// > 0: a cluster with fewer than min_cluster candidates is a focus too when its peak |z|
  /// reaches this (small but strong losses: peak or extent, as SPM reports both)
  double peak = 0;
  /// +1: only increases (hyper), -1: only decreases (hypo), 0: both (clusters never mix signs)
  int sign = 0;
  SingleCaseTest test = SingleCaseTest::z;
  /// > 0: threshold-free cluster enhancement (vpm/tfce.hpp) instead of the cut and the cluster
  /// size: a focus is a connected set of elements of one sign with |z| >= extend (without extend,
  /// of the significant elements alone) holding an element whose TFCE score of sign * z reaches
  /// this level (`vpm calibrate --tfce` sets it from the normals left out: the level their maxima
  /// stay under at the stated rate, a family-wise rule). TFCE decides which foci there are, z
  /// their extent; threshold, fdr_q, min_cluster and peak are not used, relative_extent still
  /// trims, and a focus's candidates are its significant elements. 0: off (the clusters above).
  double tfce_level = 0;
};

/// An option of CompareOptions out of its range: `field` names the member (as the sidecar's
/// "options" object spells it), `problem` says what it must be.
struct CompareOptionError {
  std::string field;
  std::string problem;
};

/// The first option of `options` out of its range, or nothing. compare_to_reference refuses such
/// options; callers that name the options otherwise (command-line flags, keyword arguments) call
/// this first to word the message their way.
std::optional<CompareOptionError> compare_option_error(const CompareOptions& options);

/// A cluster of adjacent focus elements of one sign.
struct FocusCluster {
  int id = 0;                 ///< 1-based, largest first
  int sign = 1;               ///< +1 above the normals, -1 below
  std::vector<int> elements;  ///< ascending
  /// its elements at or beyond the cut (the rest joined by CompareOptions::extend): the count
  /// min_cluster is held against, so one comparison at min_cluster 1 tells which clusters any
  /// larger min_cluster keeps (bench/cohort/lono.py calibrates it that way); with
  /// CompareOptions::relative_extent counted before the trim, so some may lie outside `elements`
  int candidates = 0;
  double volume = 0;          ///< ball volume (sum of element volumes; the ball is 4 pi / 3)
  int peak_element = -1;
  double peak_z = 0;
  double peak_tfce = 0;       ///< with CompareOptions::tfce_level: the focus's highest TFCE score (else 0)
  /// with a calibration (vpm/calibration.hpp family_p_values): the chance that a subject
  /// without a focus shows a focus this strong anywhere (a TFCE score this high, or a cluster as
  /// large or as strong), from the normals left out; -1: not known
  double p_family = -1;
};

struct Comparison {
  std::vector<double> patient; ///< the patient's normalised feature per element (NaN: no data)
  /// per element, the reference's value for this patient: its mean, or with covariates the
  /// model's prediction at the patient's covariates
  std::vector<double> expected;
  std::vector<double> covariates;  ///< the patient's design row (empty without covariates)
  std::vector<double> z;       ///< per element (NaN where the reference or the patient has no data)
  std::vector<int> cluster;    ///< per element: FocusCluster::id, 0 when not a focus
  std::vector<FocusCluster> clusters;
  double threshold_used = 0;   ///< |z| cut actually applied (the FDR threshold when fdr_q > 0)
};

/// z per element (CompareOptions::test; the patient's feature normalised and smoothed as the
/// reference's) and its foci. With a reference of covariates, `covariates` is the patient's
/// design row (covariate_row) and, with h the patient's leverage x^T (X^T X)^-1 x,
/// z = (x - prediction) / (std sqrt(1 + h - 1/n)) (the mean at the normals' centre taken as exact,
/// as without covariates, the slopes' uncertainty not), or Crawford-Howell's t
/// (x - prediction) / (std sqrt(1 + h)) with n - p - 1 degrees of freedom. With an image
/// covariate the patient's own value of that feature (in `patient`) enters its row, and the
/// model's extra column costs one more degree of freedom.
/// InputError when the definitions differ, the row does not fit the reference or an option is
/// out of range (compare_option_error).
Comparison compare_to_reference(const CanonicalElements& elements, const Reference& reference,
                                const ElementTable& patient, const CompareOptions& options = {},
                                const std::vector<double>& covariates = {});

/// {"threshold", "clusters": [{"id","sign","elements","candidates","volume","peak_element","peak_z"}]}
Json to_json(const Comparison& comparison);

/// Writes the comparison as TSV (one row per element: element, shell, triangle, patient,
/// reference_mean, reference_std, z, cluster) and its JSON sidecar (definition, reference:
/// feature, normalisation, subjects and their tables, the patient's table, options, clusters).
/// Atomic; InputError naming the path when it cannot be written.
void write_comparison(const std::string& tsv_path, const CanonicalElements& elements, const Reference& reference,
                      const std::vector<std::string>& normal_tables, const std::string& patient_table,
                      const CompareOptions& options, const Comparison& comparison);

}  // namespace vpm
