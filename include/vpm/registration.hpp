#pragma once
// Volume-preserving landmark registration inside the unit ball (Hu, Zou & Hua 2014, section 5).
//
// 1. Rigid step (5.1): the rotation about the ball centre that best maps the landmarks onto
//    the targets (Kabsch: SVD of sum p_i q_i^T, reflections refused), applied to every vertex.
// 2. Pathlines (5.2, eq. 20-21): each landmark p travels to its target q along
//      x(t) = (1 - w) [(1 - t) p + t q] + w [((1 - t)|p| + t|q|) slerp(p/|p|, q/|q|, t)],
//    w = (|p| + |q|) / 2, t in [0, 1]: straight lines near the centre, arcs near the sphere.
//    The path stays inside the ball; its velocity x'(t) is analytic.
// 3. Divergence-free field (5.3, 5.4): at each RK4 stage time t the velocity field is the
//    divergence-free RBF interpolant (vpm/rbf.hpp) of the samples (x_i(t), x_i'(t)), one per
//    landmark, so every landmark path is an exact trajectory of the flow (landmark error is
//    the RK4 truncation error only). RegistrationField::Steady instead fits one time-independent
//    field to all pathline samples of all K steps (the paper's construction).
//    Boundary: RegistrationBoundary::Tangent (default) uses the exactly tangent kernel, so the sphere
//    is invariant; RegistrationBoundary::Samples adds the paper's normal-cancelling constraints at
//    points on the sphere (tangent there only); RegistrationBoundary::None has no boundary condition.
// 4. Advection: every vertex is moved through the field with K RK4 steps (device kernel
//    register.rk4_advect_soa, the same code on the host threads otherwise); boundary vertices are put back on the
//    sphere (radial projection of the O(dt^4) drift); tets the flow inverted (discretisation
//    error of strongly sheared tets) are repaired by local untangling (vpm/untangle.hpp) when
//    possible; a result still folded is refused with NumericalError.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "vpm/error.hpp"
#include "vpm/json.hpp"
#include "vpm/landmarks.hpp"
#include "vpm/mesh.hpp"
#include "vpm/volume_map.hpp"
#include "vpm/metrics.hpp"
#include "vpm/rbf.hpp"
#include "vpm/untangle.hpp"

namespace vpm {

class Device;

/// Invalid registration input, with where the problem lies so that a caller can point at its
/// own source of the input (a file and line, an option name). what() is the whole message.
class RegistrationInputError : public InputError {
 public:
  enum class Subject {
    Landmarks,  ///< the landmark and target sets as a whole (counts, emptiness)
    Landmark,   ///< one landmark / target pair: `landmark` is its row index (0-based)
    Mesh,       ///< the mesh is not mapped to the unit ball
    Option,     ///< an option value: `option` names the RegistrationOptions member
  };
  RegistrationInputError(Subject subject, const std::string& message, int landmark = -1,
                         std::string option = {}, std::string problem = {})
      : InputError(message), subject(subject), landmark(landmark), option(std::move(option)),
        problem(std::move(problem)) {}
  Subject subject;
  int landmark;         ///< row of the landmark (Subject::Landmark), -1 otherwise
  std::string option;   ///< option name in library terms (Subject::Option), e.g. "boundary"
  std::string problem;  ///< what is wrong with the option value (Subject::Option)
};

enum class RegistrationBoundary { Tangent, Samples, None };
enum class RegistrationField { PerStep, Steady };

/// "tangent" | "samples" | "none" (RegistrationInputError with option "boundary" otherwise), and
/// back.
RegistrationBoundary parse_registration_boundary(const std::string& text);
std::string to_string(RegistrationBoundary mode);
/// "per-step" | "steady" (RegistrationInputError with option "field" otherwise), and back.
RegistrationField parse_registration_field(const std::string& text);
std::string to_string(RegistrationField mode);

struct RegistrationOptions {
  int steps = 50;                 ///< K: pathline samples / RK4 steps over t in [0, 1]
  /// Gaussian parameter lambda = 1 / width^2; 0 = automatic: width = width_factor x the mean
  /// nearest-neighbour spacing of the landmarks (the smaller of start and target sets).
  double lambda = 0;
  double width_factor = 0.5;
  /// Automatic width by leave-one-out instead: the factor in {0.5, 0.75, 1, 1.5, 2, 3} whose
  /// interpolant of the initial landmark velocities has the smallest RMS LOO error.
  bool width_loo = false;
  RegistrationBoundary boundary = RegistrationBoundary::Tangent;
  RegistrationField field = RegistrationField::PerStep;
  int boundary_samples = 200;     ///< sphere points for RegistrationBoundary::Samples
  int normal_check_samples = 4000;  ///< sphere points where max |u . n| is measured
  bool rigid = true;              ///< do the rotation step first
  bool project_boundary = true;   ///< put boundary vertices back on the sphere afterwards
  /// Repair tets the flow inverted with the local untangler of vpm/untangle.hpp (the
  /// pre-registration map as reference, theta 0.5, `untangle_rings` rings of neighbours free;
  /// boundary vertices and vertices at landmark positions fixed) before the fold check.
  bool untangle = true;
  int untangle_rings = 2;
  /// After the flow (and any untangling), give back the volume the linear tets lost under the
  /// flow: polish rounds of the volume map (vpm/volume_map.hpp, polish_only) with the
  /// pre-registration map as reference, the boundary sliding on the sphere, vertices used as
  /// landmarks pinned and each moved landmark held where the flow put it: an anchor
  /// (VolumeAnchor: its barycentric point in its tet stays, the tet's vertices may move), or its
  /// tet's four vertices pinned where that tet touches the boundary. Each polish step is
  /// fold-checked and kept only if it lowers the tet distortion.
  bool restore_volumes = true;
  /// CGLS iterations per polish step of the restoration (up to 30,000 tets; times
  /// cbrt(tets / 30,000) above, so that a step reaches as far in the ball on finer meshes), and
  /// at most `restore_rounds` steps. Few iterations keep each step local (CGLS reaches the
  /// smooth, far-reaching part of the correction last), so the restoration drifts the registered
  /// regions less: on five demo subjects (docs/register.md) 5 / 10 / 20 / 60 iterations gave
  /// held-out Dice 0.825 / 0.821 / 0.815 / 0.809 (no restoration 0.825) at tet mean |r-1| 1.18 /
  /// 1.07 / 1.00 / 0.97 %.
  int restore_iterations = 10;
  int restore_rounds = 12;
  /// The restoration's steps end once one lowers the tet mean |r-1| by less than this fraction.
  double restore_min_gain = 0.01;
  /// Where the restoration's polish directions are computed (VolumeMapOptions::polish):
  /// automatic = the OpenCL kernels on GPUs (image holds included), the host threads otherwise.
  ExecutionPlace restore_polish = ExecutionPlace::automatic;
  /// Throw NumericalError when tets invert (false: return the folded result and count them;
  /// for benchmarks and diagnosis only).
  bool refuse_folds = true;
  /// Steady mode: pathline samples closer than this fraction of the width are merged.
  double steady_merge_fraction = 0.25;
};

/// The RBF fits behind the flow (registration_fields).
struct RegistrationFitReport {
  RbfKernel kernel = RbfKernel::Tangent;
  int fields = 0;                ///< fields fitted (2K + 1 per-step, 1 steady)
  int samples_per_field = 0;     ///< largest number of samples (after merging) in one fit
  int merged_samples = 0;        ///< largest number of samples merged away in one fit
  int boundary_constraints = 0;  ///< sphere points of RegistrationBoundary::Samples
  double max_condition = 0;      ///< largest condition estimate (first, middle, last fit)
  int regularised_fits = 0;      ///< fits that needed regularisation
  double max_sample_residual = 0;
};
/// {"kernel": "tangent"|"free", "fields", "samples_per_field", "merged_samples",
///  "boundary_constraints", "max_condition", "regularised_fits", "max_sample_residual"}
Json to_json(const RegistrationFitReport& fit);

/// One candidate of the leave-one-out width choice (RegistrationOptions::width_loo).
struct WidthLooCandidate {
  double width_factor = 0;
  double loo_rms = 0;  ///< RMS leave-one-out error of the initial landmark velocities
};

/// The local untangling of tets the flow inverted.
struct RegistrationUntangle {
  UntangleResult result;
  int folded_by_flow = 0;  ///< tets the flow inverted (the untangler's input)
  double seconds = 0;
};
/// {UntangleResult::to_json()..., "folded_by_flow", "seconds"}
Json to_json(const RegistrationUntangle& untangle);

/// The volume restoration after the flow (RegistrationOptions::restore_volumes).
struct RegistrationRestore {
  double vertex_mean_abs_dev_before = 0;  ///< mean |r - 1| of vertex volume ratios, before
  double tet_mean_abs_dev_before = 0;     ///< mean |r - 1| of tet volume ratios, before
  double vertex_mean_abs_dev = 0;         ///< after
  double tet_mean_abs_dev = 0;            ///< after
  long rounds = 0;                        ///< polish rounds run
  int pinned_vertices = 0;                ///< vertices held in place
  int anchored_landmarks = 0;             ///< landmarks held as material points (VolumeAnchor)
  int held_points = 0;                    ///< image grid points held across their edges (VolumeHold)
  Placement placement;                    ///< where the polish ran and why (vpm/placement.hpp)
};
/// {"vertex_mean_abs_dev_before", "tet_mean_abs_dev_before", "vertex_mean_abs_dev",
///  "tet_mean_abs_dev", "rounds", "pinned_vertices", "anchored_landmarks", "held_points",
///  "placement"}
Json to_json(const RegistrationRestore& restore);

/// Seconds spent in each registration step.
struct RegistrationTimings {
  double rigid = 0, fit = 0, advect = 0, check = 0;
  std::optional<double> restore;  ///< when the volume restoration ran
  double total = 0;
};

/// What a registration did, beyond the RegistrationResult's main numbers.
struct RegistrationReport {
  std::string device;
  long vertices = 0, tets = 0, landmarks = 0;
  int steps = 0;
  double width = 0;             ///< Gaussian width 1 / sqrt(lambda)
  double landmark_spacing = 0;  ///< mean nearest-neighbour spacing the automatic width uses
  std::vector<WidthLooCandidate> width_loo;  ///< empty unless the width was chosen by LOO
  RegistrationBoundary boundary = RegistrationBoundary::Tangent;
  RegistrationField field = RegistrationField::PerStep;
  double rotation_deg = 0;       ///< angle of the rigid rotation
  int folded_by_flow = 0;        ///< tets the flow inverted (0 when untangling is off)
  int newly_inverted_tets = 0;   ///< inverted tets that were positive before the registration
  std::optional<RegistrationUntangle> untangle;  ///< when tets were untangled
  std::optional<RegistrationRestore> restore;    ///< when the volumes were restored
  RegistrationFitReport fit;
  RegistrationTimings timings;
};

struct RegistrationResult {
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< rigid step (x -> R x)
  double lambda = 0;              ///< Gaussian parameter used
  Points landmarks_final;         ///< where the flow took the landmarks (N x 3)
  double landmark_rms_error = 0;  ///< RMS |landmark_final - target| (ball units)
  double landmark_max_error = 0;
  double max_normal_velocity = 0; ///< max |u . n| over the sphere check points and field times
  double boundary_drift = 0;      ///< max | |x| - 1 | of boundary vertices before projection
  int inverted_tets = 0;
  RegistrationReport report;
};

/// The registration report: {"device", "vertices", "tets", "landmarks", "steps", "lambda",
/// "width", "landmark_spacing", "width_loo": [{"width_factor", "loo_rms"}] (when chosen by LOO),
/// "boundary", "field", "rotation_deg", "landmark_rms_error", "landmark_max_error",
/// "max_normal_velocity", "boundary_drift", "inverted_tets", "folded_by_flow",
/// "untangle": {UntangleResult::to_json(), "folded_by_flow", "seconds"} (when run),
/// "restore": {"vertex_mean_abs_dev_before", "tet_mean_abs_dev_before", "vertex_mean_abs_dev",
/// "tet_mean_abs_dev", "rounds", "pinned_vertices"} (when run), "fit": {...},
/// "timings_s": {"rigid", "fit", "advect", "check", "restore" (when run), "total"},
/// "newly_inverted_tets"}
Json to_json(const RegistrationResult& result);

/// Rotation R (det +1) minimising sum |R p_i - q_i|^2 over rotations about the origin.
/// `from`, `to`: N x 3. Fewer than two non-collinear landmarks give a valid but not unique R.
Eigen::Matrix3d kabsch_rotation(const Points& from, const Points& to);

/// Pathline point x(t) from p to q (eq. 20-21 blend) and, if `velocity`, x'(t).
Eigen::Vector3d pathline(const Eigen::Vector3d& p, const Eigen::Vector3d& q, double t,
                         Eigen::Vector3d* velocity = nullptr);

/// The fields at the 2K + 1 RK4 stage times s * dt / 2 (per-step mode), or one steady field
/// repeated. Exposed for tests and benchmarks; `landmarks` already rotated.
std::vector<DivFreeField> registration_fields(const Points& landmarks, const Points& targets,
                                              double lambda, const RegistrationOptions& options,
                                              RegistrationFitReport* fit_report = nullptr);

/// Moves `points` (n x 3, in/out) with K RK4 steps through `fields` (2K + 1 of them, as
/// registration_fields returns) on `device`: kernels/rbf_advect.clh, one point per call on the
/// host threads, several per work item on OpenCL devices (far centres cut the same way).
void advect(Device& device, Points& points, const std::vector<DivFreeField>& fields, int steps);

/// Registers the mapped mesh: moves `ball` (n x 3 vertices of a mesh mapped to the unit ball,
/// in/out) so that `landmarks` (N x 3, ball coordinates) go to `targets` (N x 3) by a rotation
/// and a divergence-free flow tangent to the sphere. `tets` (m x 4) is used for the fold check.
/// Throws RegistrationInputError for mismatched counts, landmarks or targets outside the ball, duplicate
/// landmarks with different targets, a boundary landmark with an interior target, or a mesh
/// whose boundary is not on the unit sphere (within 1e-6), or invalid options (steps < 1, lambda
/// < 0); NumericalError when the result has
/// inverted tets (then `ball` is left unchanged).
RegistrationResult register_landmarks(Device& device, Points& ball, const Tets& tets,
                                      const Points& landmarks, const Points& targets,
                                      const RegistrationOptions& options = {});

/// The registration metrics of docs/design.md 5; `against_before` = map_metrics of the registered
/// mesh against the pre-registration map.
struct RegistrationSummary {
  double landmark_rms_error = 0, landmark_max_error = 0, max_normal_velocity = 0;
  int inverted_tets = 0;
  RatioStats vertex_volume_ratio, tet_volume_ratio;
  double boundary_max_radius_error = 0;
};
RegistrationSummary registration_summary(const RegistrationResult& result,
                                         const MapMetrics& against_before);
/// {"landmark_rms_error", "landmark_max_error", "max_normal_velocity", "inverted_tets",
///  "vertex_volume_ratio", "tet_volume_ratio", "boundary_max_radius_error"}
Json to_json(const RegistrationSummary& summary);

}  // namespace vpm
