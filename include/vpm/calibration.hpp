#pragma once
// The cluster-extent threshold set by the normals themselves (issue 35): leave-one-normal-out.
// Each normal is compared, with the patients' own options, against the reference of the other
// normals; it has no focus, so every cluster found is a false one. One pass at min_cluster 1
// gives, through each cluster's candidate count (FocusCluster::candidates), the false clusters
// that every larger min_cluster would keep; the calibration is the smallest min_cluster whose
// false clusters stay at or under a stated rate per 10 normals. `vpm calibrate` runs it and
// `vpm compare --min-cluster-from` applies it (bench/results/cohort_calibration/).
// Optionally the same pass sets the peak rule's level too (CompareOptions::peak: a cluster under
// min_cluster is a focus when its peak is stronger than the normals' false ones;
// bench/results/cohort_peak/).
#include <string>
#include <vector>

#include "vpm/elements.hpp"
#include "vpm/json.hpp"
#include "vpm/reference_sums.hpp"
#include "vpm/statistics.hpp"

namespace vpm {

/// What the comparisons are and the rate to hold.
struct CalibrationSettings {
  std::string feature;
  Normalisation normalisation = Normalisation::proportional;
  int smoothing = 0;          ///< rings, as build_reference's
  double shrinkage = 0;       ///< Reference::shrinkage
  CompareOptions compare;     ///< the patients' options; its min_cluster is what is calibrated (ignored)
  std::vector<std::string> covariates;  ///< Covariates::names of the reference's model (empty: none)
  std::string image_covariate;          ///< Reference::image_covariate (empty: none)
  double rate = 1.0;          ///< false clusters per 10 normals allowed (>= 0)
  /// true: the calibration sets the peak rule's level too (compare.peak must then be 0): the
  /// lowest level at which the left-out normals' clusters whose peak |z| reaches it stay at or
  /// under half the rate, strictly beyond the next such peak (at 0.01 resolution; the threshold
  /// when every cluster may pass; 0, off, when that peak is infinite: a reference without
  /// spread somewhere); min_cluster then holds the whole rate with that rule applied
  bool calibrate_peak = false;
  /// true: the calibration sets CompareOptions::tfce_level too (vpm/tfce.hpp; compare.peak and
  /// calibrate_peak must then be off): the lowest level strictly beyond the (k + 1)-th highest of
  /// the left-out normals' largest TFCE scores, k = floor(rate x normals / 10), so that at most
  /// k of them (rate/10 of the subjects: a family-wise rate per subject) show a focus. The cluster
  /// curve and min_cluster are calibrated as without it.
  bool calibrate_tfce = false;
};

/// One normal left out: how many clusters it showed at min_cluster 1 (their sizes and peaks are
/// folded into ClusterCalibration::sizes and ::strong, so that a calibration of thousands of
/// normals holds no list of their clusters).
struct LeftOutNormal {
  std::string name;
  int clusters = 0;
  int largest = 0;        ///< candidates of its largest cluster (0: none)
  double strongest = 0;   ///< |peak_z| of its strongest cluster (0: none; infinite where the reference has no spread)
  double tfce_max = 0;  ///< with CalibrationSettings::calibrate_tfce: its highest TFCE score (both signs compared)
};

/// A left-out normal's cluster that the peak rule can keep, small as it is.
struct StrongCluster {
  int normal = 0;      ///< index into ClusterCalibration::per_normal
  int candidates = 0;  ///< FocusCluster::candidates
  double peak_z = 0;
};

struct ClusterCalibration {
  CalibrationSettings settings;
  int normals = 0;
  /// false_clusters[m - 1]: the clusters over all left-out normals that min_cluster m keeps,
  /// for m = 1 .. (largest candidate count + 1) (the last entry is 0 unless a peak rule keeps
  /// small clusters).
  std::vector<int> false_clusters;
  /// The smallest min_cluster with false_clusters * 10 / normals <= rate; 0 when none is (a
  /// peak rule keeps clusters at every size: lower CompareOptions::peak or raise the rate).
  int min_cluster = 0;
  /// the peak rule's level the curve and min_cluster hold with: the calibrated one
  /// (CalibrationSettings::calibrate_peak), else settings.compare.peak (0: off)
  double peak = 0;
  /// sizes[c]: the clusters with c candidates over all normals left out, at min_cluster 1
  std::vector<long> sizes;
  /// The clusters a peak rule can keep: with a calibrated level the k + 1 of highest |peak_z|
  /// (k: the clusters half the rate allows; the level lies beyond the (k + 1)-th), strongest
  /// first; with a fixed level every cluster reaching it; none without a peak rule.
  std::vector<StrongCluster> strong;
  std::vector<LeftOutNormal> per_normal;
  /// with CalibrationSettings::calibrate_tfce: the TFCE level (else 0)
  double tfce_level = 0;
  /// The false clusters min_cluster m keeps over all left-out normals (0 past the curve's end
  /// unless a peak rule keeps small ones), and that per 10 normals.
  long clusters_at(int m) const;
  double rate_at(int m) const;
};

/// Leave-one-normal-out over `normals` (at least 4; `names` name them in messages and the
/// result); with covariates, `design` has the normals' rows (covariate_design) and each normal
/// left out is compared at its own. InputError as build_reference and compare_to_reference, or
/// on a negative rate, or a design that does not match settings.covariates.
ClusterCalibration calibrate_min_cluster(const CanonicalElements& elements, const std::vector<ElementTable>& normals,
                                         const std::vector<std::string>& names, const CalibrationSettings& settings,
                                         const CovariateDesign& design = {});

/// The same streaming (vpm/reference_sums.hpp): `totals` are the sums of every normal (at least
/// 4), made with the settings' recipe; each normal of `left_out` (named as in totals.normals(), a
/// subset of them or all) is read once, taken out of the totals and compared with the rest, in
/// parallel, a normal at a time per thread. Memory is a few references, whatever the number of
/// normals. InputError when the recipes differ or a normal left out is not in the totals.
ClusterCalibration calibrate_min_cluster(const CanonicalElements& elements, const ReferenceSums& totals,
                                         const NormalSource& left_out, const CalibrationSettings& settings);

/// {"feature", "normalisation", "smoothing", "shrinkage", "covariates" (names), "image_covariate"
/// ("" for none), "options": {threshold, fdr_q, extend, peak (the fixed one; 0 when
///  calibrated), sign, test}, "rate", "normals", "min_cluster", "calibrate_peak", "peak" (the
///  level applied), "curve": [{"min_cluster", "false_clusters", "per_10_normals"}],
///  "sizes": [clusters with 0, 1, 2, ... candidates], "strong": [{"normal", "candidates", "peak_z"}],
///  "per_normal": [{"normal", "clusters", "largest", "strongest" (null: infinite), "tfce_max" (with
///  calibrate_tfce)}],
///  "tfce" (calibrate_tfce),
///  "tfce_level" (0 without)}
Json to_json(const ClusterCalibration& calibration);

/// What a calibration sets in a comparison: CompareOptions::min_cluster and ::peak.
struct CalibratedRule {
  int min_cluster = 0;
  double peak = 0;  ///< the calibrated level, or the comparison's own fixed one
  double tfce_level = 0;  ///< a TFCE calibration's level (CompareOptions::tfce_level), else 0
  /// a TFCE calibration's per-normal maxima, highest first: a focus's family-wise p-value is
  /// (1 + the maxima at or above its peak score) / (1 + their number)
  std::vector<double> tfce_null;
  /// without TFCE: each normal's largest cluster (candidates) and strongest |peak_z| (empty for
  /// a file without them), the null of family_p_values
  std::vector<std::pair<int, double>> cluster_null;
};

/// The rule of a calibration JSON written by to_json (a file from elsewhere: checked), after
/// checking that it was made with `settings` (feature, normalisation, smoothing, shrinkage,
/// covariates and image covariate (absent in a file: none) and every compare option but
/// min_cluster, the peak being 0 in both when the calibration set it) and on the normals named
/// `normals` (the same set, any order): InputError naming `source` and the first difference.
/// A file without "calibrate_peak" (written by an older vpm) sets no peak; one without "tfce" no
/// TFCE level.
CalibratedRule calibrated_rule(const Json& calibration, const CalibrationSettings& settings,
                               const std::vector<std::string>& normals, const std::string& source);

/// FocusCluster::p_family of every focus of `comparison` from its calibration's null, the normals
/// left out: with TFCE (rule.tfce_null) (1 + the normals' maxima at or above the focus's peak
/// score) / (1 + their number). Else (rule.cluster_null) the cluster rule's two statistics are
/// combined by their smaller rank (Tippett's min-p over the normals left out): a cluster's rank is
/// the number of normals whose largest cluster has at least its candidates or, if fewer, whose
/// strongest has at least its |peak_z|; the p-value is (1 + the normals whose own rank is at or
/// below the focus's) / (1 + their number): the chance that a subject without a focus shows a
/// cluster as extreme, in size or in peak, anywhere. Nothing without a null.
void family_p_values(Comparison& comparison, const CalibratedRule& rule);

}  // namespace vpm
