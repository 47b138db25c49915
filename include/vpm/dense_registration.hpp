#pragma once
// Dense volume-preserving registration (issue 13): the landmark registration of
// vpm/registration.hpp followed by iterations that pull the subject onto the template (its
// labelled regions' boundaries, its image intensities, or both), each by a divergence-free flow
// tangent to the sphere, so volumes stay preserved and the ball stays the domain.
//
// One iteration, at Gaussian width w (coarse to fine over DenseRegistrationOptions::widths):
// 1. Force (DenseRegistrationOptions::force):
//    * labels: the region boundaries are the faces between tets of different labels (label > 0,
//      regions in `exclude_labels` counted as unlabelled so a held-out region is never seen).
//      For every region both meshes carry, each subject boundary face is matched to the closest
//      template boundary face of the same region (displacement q - p) and each template face to
//      the closest subject face (displacement q - p placed at the subject face): symmetric
//      closest-point matches, weighted by face area.
//    * image: both subjects' images (DenseImages) are read on a regular grid of `image_grid`
//      cells across the ball through their maps (ball point -> native position -> trilinear
//      voxel), the subject's scaled to the template's mean and spread; at every centre of the
//      field (step 2) the least-squares system of the translation that best explains the local
//      difference over the grid points around it (Gaussian weights of width `smoothing` x w;
//      Lucas-Kanade with the mean gradient of the two images).
//    * both: the mean of the two at each centre.
//    The force is not reduced to one translation per centre: each centre keeps its local
//    least-squares system (the image's structure tensor sum w g g^T and sum w g (S - T); the
//    matches' mass and mean) and the field is fitted to all of them at once (vpm/rbf.hpp,
//    fit_divfree_weighted), so an edge constrains only the motion across it and flat white
//    matter nothing: the field there follows from its neighbours instead of being held still.
// 2. Smoothing (labels): the matches are averaged with a Gaussian of width `smoothing` x w at centres on
//    a grid of spacing `centre_spacing` x w in the ball (sum w_i g_i d_i / (sum w_i g_i + 1), so
//    centres without data ask for no motion).
// 3. Projection: the divergence-free tangent RBF field (vpm/rbf.hpp, RbfKernel::Tangent) fitted
//    to the centre values with a smoothing ridge: exactly divergence-free and tangent to the
//    sphere, whatever the force was.
// 4. Step: every vertex (and every landmark) is advected through `step` x the field with RK4;
//    boundary vertices are put back on the sphere; tets the flow inverted are untangled locally
//    (the positions before the step as reference). The iteration is kept only when it leaves no
//    inverted tet and improves the force's own measure: the label agreement (mean Dice of the
//    force's regions, tet labels at ball grid points) for `labels`, the image mismatch (mean
//    squared difference on the image grid / the template's variance) for `image` and `both`;
//    otherwise it is undone and the level ends.
// After the iterations, a landmark flow (register_landmarks without rotation) takes the landmarks
// from where the dense flows left them back exactly onto their targets, and the volume
// restoration of the landmark registration runs once against the map before registration
// (with an image force: holding the image's edges, `restore_image_weight`).
#include <Eigen/Core>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "vpm/image.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/registration.hpp"
#include "vpm/timing.hpp"

namespace vpm {

class Device;

/// What the dense force pulls on (see the top of this header).
enum class DenseForce { labels, image, both };

/// "labels", "image", "both"; and back (InputError naming the accepted words otherwise).
const char* to_string(DenseForce force);
DenseForce dense_force_from_string(const std::string& word);

/// The images of an intensity-driven dense registration (DenseForce::image or both): each
/// subject's image in its own native space (world mm), and the native positions of its ball
/// mesh's vertices (the mesh field original_position), row for row.
struct DenseImages {
  const Image* subject = nullptr;
  Points subject_native;
  const Image* templ = nullptr;
  Points template_native;
};

/// The image refinement that can end a dense registration with an image force (DenseForce::image
/// or both), after the landmark correction and before the final volume restoration: every
/// interior vertex of the subject's ball mesh moves at once, by L-BFGS on
///   E(x) = mean over the subject's voxels of (S - T(x_p))^2 / var(T)
///          + volume_weight x mean over tets of log(V_t(x) / V0_t)^2
/// (V0: the subject's mapped ball, the reference of every volume measure). Each voxel inside the
/// subject's native mesh is a fixed barycentric point p of its tet, so its ball position x_p
/// moves with the vertices; S is the subject's voxel value scaled linearly to the template's
/// mean and spread there, T the template's image resampled through its map on a ball grid as
/// fine as its voxels (trilinear, with its gradient). Sphere vertices stay; the landmarks move
/// with their tets (region centroids are starting correspondences about 0.01 ball units from the
/// truth: held on their targets they cost held-out overlap), so their errors are reported, not
/// required. A trial step that inverts a tet is halved. The RBF flows' alignment is limited by
/// their width (0.14 ball units at the finest level); this one by the mesh and the voxels
/// (docs/register.md, "The image refinement").
struct DenseRefineOptions {
  int iterations = 0;         ///< L-BFGS iterations at most; 0 = no refinement
  double volume_weight = 1;   ///< weight of the volume term against the image mismatch
  double smoothing_mm = 1;    ///< Gaussian smoothing (mm) of both images before the comparison
  int memory = 8;             ///< L-BFGS memory (pairs)
  double min_gain = 1e-6;     ///< stop once an iteration lowers E by less than this fraction
  /// An image term below this (1e-4 of the template's variance) is the resampling's own error:
  /// nothing is moved (a subject registered to itself stays the identity).
  static constexpr double kAligned = 1e-4;
};

struct DenseRegistrationOptions {
  DenseForce force = DenseForce::labels;  ///< what pulls (images required for image and both)
  /// Cells across the ball of the image force's grid (and of the image mismatch that decides
  /// whether an iteration is kept); 0 = automatic, dense_image_grid_cells(subject tets): about
  /// two grid points per tet, so the grid follows the mesh's resolution (48 at the paper's 26k
  /// tets, 96 at the workflow's 213k; bench/results/register_force/).
  int image_grid = 0;
  /// Gaussian smoothing of both images' grid values before the image force, x the level's width
  /// (coarse levels see coarse features: a larger capture range).
  double image_smoothing = 0;
  /// Dense iterations in all, split evenly over the widths (coarse first); 0 = landmark
  /// registration only (the result is then register_landmarks' alone).
  int iterations = 0;
  std::vector<double> widths = {0.3, 0.2, 0.14};  ///< Gaussian widths of the levels (ball units)
  double step = 0.8;            ///< fraction of the smoothed displacement taken per iteration
  double centre_spacing = 1.0;  ///< grid spacing of the field's centres, x the width
  double smoothing = 0.5;       ///< width of the Gaussian averaging the matches, x the width
  double ridge = 0.3;           ///< smoothing ridge of the fit, x the mean Gram diagonal
  /// Relative residual of the fit's conjugate gradients: a field is a step
  /// of a fraction of a voxel's worth of ball units, so 1e-6 of it is far below anything an
  /// iteration resolves (1e-6 and 1e-10 gave the same Dice and volumes at 213k tets; 1e-10
  /// takes 93 instead of about 55 Gram products at width 0.1).
  double fit_tolerance = 1e-6;
  /// RK4 steps per iteration. One: an iteration moves vertices by a small fraction of its
  /// width (about a tenth at most, measured), where one step and four gave the same Dice,
  /// volumes and folds on five pairs at 213k tets (docs/register.md); each step costs as much.
  int advect_steps = 1;
  std::vector<int> exclude_labels;  ///< regions the force never sees (held out)
  int agreement_grid = 40;      ///< cells per axis of the ball grid for the label agreement
  /// Cycles of (volume restoration, then iterations/widths more dense iterations at the finest
  /// width) after the coarse-to-fine iterations: each restoration gives back the volume the
  /// flows lost (they are divergence-free only up to their discretisation), and the iterations
  /// after it pull the restored mesh onto the template again, so the image force keeps working
  /// on a volume-preserving configuration (docs/register.md, "Restore cycles"). 0: restore once
  /// at the end only.
  int restore_cycles = 0;
  /// Move the landmarks back exactly onto their targets after the dense iterations.
  bool exact_landmarks = true;
  /// With an image force: the final volume restoration holds the image grid points across
  /// their edges (VolumeHold rows weighing this x the number of tets against the volume rows),
  /// so restoring volumes does not slide structures off what the images aligned; 0 = off.
  double restore_image_weight = 300;
  /// The image refinement after the landmark correction.
  DenseRefineOptions refine;
  /// Time budget (vpm/timing.hpp), checked before every dense iteration: when it has passed the
  /// iterations stop there (DenseRegistrationResult::time_budget_spent) and the landmarks and
  /// volumes are still restored, so the result is a valid registration, less aligned.
  Deadline deadline{};
  /// Called with one line per dense iteration (progress display); may be empty.
  std::function<void(const std::string&)> progress;
};

/// The automatic image grid (DenseRegistrationOptions::image_grid = 0) for a subject of `tets`
/// tets: the cells across the ball whose grid points inside it number about 2.2 per tet,
/// round(cbrt(6 x 2.2 x tets / pi)), within [24, 128]. At 213k tets the 96 it gives aligned
/// held-out structures 0.004-0.009 Dice better than 48, whose mismatch stopped the finer levels
/// early; at 26k tets 96 aligned them worse than 48 and took 1.7x the time.
int dense_image_grid_cells(long tets);

/// One dense iteration.
struct DenseIteration {
  double width = 0;
  long matches = 0;               ///< closest-point matches (both directions)
  int centres = 0;                ///< centres of the fitted field
  double mean_match_distance = 0; ///< area-weighted mean |q - p| of the matches (ball units)
  double max_move = 0;            ///< largest vertex displacement of the step
  double agreement = 0;           ///< label agreement after the step
  double mismatch = -1;           ///< image mismatch after the step (-1: no image force)
  long image_points = 0;          ///< grid points of the image force
  double mean_translation = 0;    ///< mean length of the image force's translations at the centres
  int folded = 0;                 ///< tets the step inverted (before untangling)
  bool accepted = false;
  double seconds = 0;
};
/// {"width", "matches", "centres", "mean_match_distance", "max_move", "agreement", "folded",
///  "accepted", "seconds"} and "mismatch", "image_points", "mean_translation" with the image force
Json to_json(const DenseIteration& iteration);

/// What the image refinement did.
struct DenseRefineReport {
  long samples = 0;             ///< subject voxels compared
  int template_cells = 0;       ///< cells across the ball of the template's resampled image
  int pinned_vertices = 0;      ///< sphere vertices held still
  int iterations = 0;           ///< L-BFGS iterations taken
  double mismatch_before = 0, mismatch_after = 0;  ///< the image term of E
  double volume_before = 0, volume_after = 0;      ///< mean log(V / V0)^2
  double seconds = 0;
};
/// {"samples", "template_cells", "pinned_vertices", "iterations", "mismatch_before",
///  "mismatch_after", "volume_before", "volume_after", "seconds"}
Json to_json(const DenseRefineReport& report);

struct DenseRegistrationResult {
  RegistrationResult landmark;                ///< the landmark registration (first stage)
  std::optional<RegistrationResult> correction;  ///< the final landmark flow (when run)
  std::optional<RegistrationRestore> restore;    ///< the final volume restoration (when run)
  std::optional<DenseRefineReport> refine;       ///< the image refinement (when run)
  std::vector<DenseIteration> iterations;
  std::vector<int> regions;       ///< labels the force used
  double agreement_before = 0;    ///< label agreement of the mapped mesh
  double agreement_landmarks = 0; ///< after the landmark registration
  double agreement_after = 0;     ///< at the end
  /// The image mismatch at the same three stages (-1: no image force).
  double mismatch_before = -1, mismatch_landmarks = -1, mismatch_after = -1;
  DenseForce force = DenseForce::labels;
  double landmark_rms_error = 0, landmark_max_error = 0;  ///< at the end (ball units)
  double max_normal_velocity = 0; ///< largest max |u . n| of all flows
  int inverted_tets = 0;          ///< at the end
  bool time_budget_spent = false; ///< DenseRegistrationOptions::deadline stopped the iterations
  double seconds_landmark = 0, seconds_dense = 0, seconds_correction = 0, seconds_refine = 0,
         seconds_restore = 0, seconds_total = 0;
};
/// {"landmark": to_json(RegistrationResult), "correction", "refine", "restore" (each when run),
///  "iterations": [...], "regions", "agreement_before", "agreement_landmarks", "agreement_after",
///  "force", "mismatch_before", "mismatch_landmarks", "mismatch_after" (with the image force),
///  "landmark_rms_error", "landmark_max_error", "max_normal_velocity", "inverted_tets",
///  "timings_s": {"landmark", "dense", "correction", "refine", "restore", "total"}}
Json to_json(const DenseRegistrationResult& result);

/// The mapped mesh being registered: `ball` n x 3 (in: the mapped positions; out: the
/// registered ones), `tets` m x 4, `labels` m tet labels (atlas regions; empty: none).
struct DenseSubject {
  Points& ball;
  const Tets& tets;
  const std::vector<int>& labels;
};

/// The labelled mapped template the subject is registered to.
struct DenseTemplate {
  const Points& ball;
  const Tets& tets;
  const std::vector<int>& labels;
};

/// Registers the labelled mapped mesh `subject` to the labelled `templ`: landmark registration
/// of `landmarks` onto `targets` with `landmark_options` (their volume restoration deferred to
/// the end when dense iterations run), then the dense iterations.
/// `images` is required for DenseForce::image and both (and unused for labels).
/// Throws what register_landmarks throws, InputError for label counts that do not match the
/// tets, invalid options (widths <= 0, step outside (0, 1], iterations < 0), an image force
/// without images or with native positions that do not match the meshes, and
/// NumericalError when the final result would have inverted tets (subject.ball then unchanged).
DenseRegistrationResult register_dense(Device& device, const DenseSubject& subject, const DenseTemplate& templ,
                                       const Points& landmarks, const Points& targets,
                                       const RegistrationOptions& landmark_options,
                                       const DenseRegistrationOptions& options,
                                       const DenseImages* images = nullptr);

}  // namespace vpm
