#pragma once
// What the collective view shows (paper 6.2, Figs. 8-10; docs/view.md): a cohort's subjects,
// each with the same canonical surfaces (one per shell, the icosphere one level finer than the
// elements, at the shell's middle radius) pulled back to its native space through its
// registered map, its per-element feature values and z-scores against the normals, and for
// each patient its foci in native space and its image with the z-map for slice views.
// Typed data only: vpm/view_page.hpp turns it into a web page.
#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "vpm/elements.hpp"
#include "vpm/mesh.hpp"
#include "vpm/statistics.hpp"

namespace vpm {

/// One focus cluster of a patient, as `vpm compare` measured it in native space.
struct ViewFocus {
  int id = 0;                 ///< FocusCluster::id (1 = largest)
  double volume_mm3 = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();  ///< world mm
  double peak_z = 0;
  int peak_element = -1;
  int label = 0;              ///< main atlas label under the focus (0: none)
};

/// A patient's image of one feature and its z-map on (every `step`-th voxel of) the image's own
/// grid, for slice views.
struct ViewSlices {
  std::array<int, 3> dims{0, 0, 0};
  Eigen::Matrix4d affine = Eigen::Matrix4d::Identity();  ///< voxel (of the subsampled grid) -> world mm
  int step = 1;
  std::string source;                ///< the image file (absolute; the page shows it relative to itself)
  std::vector<std::uint8_t> image;   ///< intensity scaled to 0..255 (0 and the 99.5th percentile)
  std::vector<std::int8_t> z;        ///< round(z * z_scale), clamped to +-127
  double z_scale = 10;
};

struct ViewSubject {
  std::string id;
  bool patient = false;
  /// shells x display vertices x 3 (mm): display vertex v of shell k at ball point
  /// sphere(v) * mid_radius(k), pulled back through the registered mesh.
  std::vector<float> native;
  std::map<std::string, std::vector<float>> values;  ///< per feature: normalised value per element
  /// patients, per feature: z per element as vpm compare computed it. (A normal's z is leave-one-out,
  /// leave_one_out_z; the page computes it from the normal's values and the reference's mean,
  /// standard deviation and count, so it is not held here.)
  std::map<std::string, std::vector<float>> z;
  std::map<std::string, int> foci_count;             ///< patients: clusters per feature
  std::map<std::string, std::vector<std::int32_t>> cluster;  ///< patients: per feature, focus id per element (0: none)
  std::map<std::string, std::vector<ViewFocus>> foci;  ///< patients: per feature
  std::vector<float> centres;  ///< patients: native position of each element's centre (elements x 3)
  std::map<std::string, ViewSlices> slices;  ///< patients: per feature with an image and z-map
};

struct ViewFeature {
  std::string name;
  Normalisation normalisation = Normalisation::proportional;
  int smoothing = 0;          ///< Reference::smoothing
  double shrinkage = 0;       ///< Reference::shrinkage
  /// Reference::covariate_names (empty: none). Patients' z are then against their own
  /// predictions; `mean` is the model at the normals' mean covariates, so the page's
  /// leave-one-out z of a normal is exact only for a normal at those covariates.
  std::vector<std::string> covariates;
  /// Reference::image_covariate (empty: none); patients' z are against the value their own
  /// structure predicts, and the page's leave-one-out z of a normal ignores it, as covariates
  std::string image_covariate;
  CompareOptions compare;     ///< the options `vpm compare` used
  int reference_subjects = 0;
  std::vector<float> mean, std;  ///< the reference per element
  std::vector<int> count;        ///< per element: the normals with data there
};

struct CohortView {
  std::string title;
  /// The elements drawn: the tables' up to CohortViewOptions::max_display_level, coarser above it
  /// (every per-element array below is over these; docs/view.md "Tables finer than the page").
  ElementDefinition definition;
  ElementDefinition compared;  ///< the tables' elements, which vpm compare used
  std::vector<double> mid_radii;          ///< per shell: the radius halving its volume
  TriSurface display;                     ///< unit icosphere, one level finer than the elements below level 4, else theirs
  std::vector<int> display_triangle_element;  ///< per display triangle: its element triangle
  std::vector<ViewFeature> features;
  std::vector<int> element_label;         ///< per element: template atlas label at its centre (empty: none)
  std::map<int, std::string> label_names; ///< atlas label -> region name (may be empty)
  std::vector<ViewSubject> subjects;      ///< patients first, then normals, each by id
};

struct CohortViewOptions {
  std::string feature;        ///< only this feature ("" = every feature compared)
  std::string template_mesh;  ///< the template's ball mesh ("" = RESULTS/template/template_ball.vtu if present)
  std::string label_names;    ///< atlas names: lines "id name [...]" (e.g. mricron's aal.nii.txt)
  std::string title;
  long max_slice_voxels = 400000;  ///< patients' images are subsampled to at most this many voxels
  /// Tables of a finer level are drawn at this one: each display element shows the mean of the
  /// values and z of the finer elements whose centres it holds (spreads: root mean square;
  /// counts: the least; focus ids: the most frequent). At level 6 a page would hold 7.7 times the
  /// values and 16 times the surfaces of level 5's (539 MB for 10 subjects instead of 10 MB).
  int max_display_level = 5;
};

/// The radius of each shell that halves its volume: cbrt((r_k^3 + r_{k+1}^3) / 2).
std::vector<double> shell_mid_radii(const CanonicalElements& elements);

/// The element triangle of each triangle of `display` (a finer unit icosphere).
std::vector<int> display_triangle_elements(const CanonicalElements& elements, const TriSurface& display);

/// Native positions (shells x vertices x 3) of the display sphere's vertices at every shell's
/// middle radius, pulled back through `registered` (a registered ball mesh with the point field
/// original_position; InputError otherwise).
std::vector<float> native_shell_surfaces(const CanonicalElements& elements, const TriSurface& display,
                                         const TetMesh& registered);

/// Native positions (elements x 3) of every element's centre (its triangle's centroid direction
/// at the shell's middle radius) through `registered`.
std::vector<float> native_element_centres(const CanonicalElements& elements, const TetMesh& registered);

/// Each normal's z against the reference of the other normals (leave-one-out; sample standard
/// deviation): x[i][e] is normal i's value at element e. NaN where fewer than 4 normals have a
/// finite value or the others' spread is 0. A normal compared with a reference that holds it
/// would look closer to the normals than a patient does. The cohort page computes the same from
/// a normal's value and the reference's mean, standard deviation and count (web/src/cohort.js).
std::vector<std::vector<double>> leave_one_out_z(const std::vector<std::vector<double>>& x);

/// Reads a cohort from the workflow's results folder (docs/cohort.md): the comparisons
/// compare/*.json (patients; their reference tables name the normals), each subject's table and
/// registered mesh, the template's ball mesh for atlas regions, each patient's image (from its
/// table) and z-map (compare/<name>_z.nii.gz) and foci table. InputError naming the file when
/// something is missing, malformed, or inconsistent (tables of different element definitions;
/// a comparison whose foci no longer match its tables).
CohortView load_cohort_view(const std::string& results_dir, const CohortViewOptions& options = {});

}  // namespace vpm
