#pragma once
// The initial (fold-free) map of a tet mesh to the closed unit ball (paper 4.1; docs/design.md 4.1
// steps 1-4):
//
//  1. split: every interior edge whose two ends are boundary vertices is split at its midpoint
//     (all tets around it are halved), repeated up to `max_split_rounds` times; a tet whose
//     four vertices are on the boundary with all six edges on the boundary surface (no
//     interior edge left to split) is split 1 -> 4 at its centroid. Afterwards no tet has four
//     boundary vertices. Inserted vertices come after the input ones (input order kept).
//  2. boundary -> sphere: spherical conformal map with linear solves only (Choi, Lam & Lui
//     2015): planar harmonic map of the surface minus its most regular triangle onto that
//     triangle, inverse stereographic projection (rescaled so the north and south triangles
//     have comparable size), south-pole correction (quasi-conformal composition through the
//     linear Beltrami solver, the 10% of vertices nearest the south pole fixed), orientation
//     check (mirrored if reversed), Moebius balancing (hyperbolic translations of the ball that
//     move the input-area-weighted centroid of the sphere points to the origin; kept only if it
//     does not raise the mean |area ratio - 1|), optionally an
//     area-equalising flow on the sphere. Steps that would flip a boundary triangle are
//     undone and reported.
//  3. interior: harmonic map (P1 cotangent stiffness of the refined input mesh, Dirichlet on
//     the boundary), solved on the host (Eigen) or by the shared solver on the device.
//  4. untangle: vpm::untangle (Garanzha et al. 2021) with the boundary fixed; the reference
//     shape of each tet is the refined input tet scaled to the ball mesh's volume.
//  When steps 2-4 with the equal-area sphere map leave a fold, they are redone with the
//  conformal sphere map (report.fallback says so).
//  5. refine: a fixed boundary on the sphere can leave a tet mesh no fold-free interior (an
//     armadillo's tet pinned at det -5e-12, a dinosaur's feet); when folds remain, the interior
//     edges of the tets within 1, 2, 4 rings of them are split at their midpoints (the boundary
//     untouched, inserted vertices after the others) and step 4 runs again on the refined
//     mesh, up to `max_refine_rounds` times (report.refine says so).
//
// A map that is still folded after step 4 is never returned: NumericalError (exit 3) with the
// number of folded tets, where they are, and the smallest dihedral angle of the input (meshes
// with slivers of 0.01-0.05 degrees are known to defeat this pipeline, docs/design.md 4.2).
#include <functional>
#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vpm/placement.hpp"
#include "vpm/solver.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/metrics.hpp"
#include "vpm/timing.hpp"
#include "vpm/untangle.hpp"

namespace vpm {

class Device;
class PoissonSolver;

struct InitialMapOptions {
  // ---- step 1: edge split
  bool split_edges = true;        ///< false: keep the input connectivity (tets with four
                                  ///< boundary vertices then usually flatten on the sphere)
  int max_split_rounds = 4;
  // ---- step 2: boundary -> sphere
  bool south_pole_correction = true;
  bool moebius_balance = true;
  int moebius_max_iterations = 200;
  double moebius_tolerance = 1e-9;   ///< stop when |area-weighted centroid| is below this
  /// Area-equalising flow on the sphere after balancing (for users who freeze the boundary
  /// during the Moser rounds; the sliding boundary does not need it). Off by default.
  bool area_correction = false;
  int area_correction_steps = 30;
  /// What the sphere map equalises after the conformal map and balancing: nothing (conformal)
  /// or each boundary vertex's share of the surface area (area), by a log-density Moser flow on
  /// the sphere (map/sphere_density.cpp), so that protrusions are not squeezed exponentially
  /// as in the conformal map. Never flips a triangle; kept only when it brings the sphere areas
  /// closer to the target. (Shares of the volume each boundary vertex encloses were tried as
  /// the target and were worse on every shape measured: docs/shapes.md.)
  enum class SphereDensity { conformal, area };
  SphereDensity sphere_density = SphereDensity::area;
  /// Where the area equalisation's Laplacian systems are solved (one per step): host = sparse
  /// Cholesky, an earlier step's factor reused as CG preconditioner; device = AMG-CG on the
  /// OpenCL device sphere_map() is given (the host when it is given none or the host device; a
  /// step whose CG fails is redone on the host); automatic (the default) = device on GPUs for
  /// boundaries of at least kDeviceDensityVertices vertices, else host (place_work,
  /// vpm/placement.hpp):
  /// on CPU devices the kernels share the cores with the Poisson solver being built beside
  /// them and lose inside `vpm map` (bench/results/volume_map_10m_cpu_again/).
  using DensitySolve = ExecutionPlace;
  DensitySolve density_solve = DensitySolve::automatic;
  int density_max_steps = 300;
  double density_tolerance = 0.02;  ///< stop at this area distortion (mean |area ratio - 1|)
  /// Where the sphere map starts. automatic: the conformal map, and when that leaves chord
  /// triangles facing inwards (long tubes and limbs shrink by e^(-length / radius) in a
  /// conformal map, below double precision) or stays crowded after the area equalisation
  /// (SphereMapReport::kCrowdedMisfit) two other starts, each equalised, the one with the
  /// smallest log misfit kept: a progressive embedding (the surface simplified to a
  /// tetrahedron by edge collapses and rebuilt on the sphere vertex by vertex, every move
  /// checked to keep each triangle facing outwards: flip-free by construction) and an axial
  /// map (the surface as a cylinder between its two farthest vertices, each band between two
  /// heights given its share of the area: for tubes, whose progressive embedding leaves the
  /// ends crushed). progressive, axial: that start always (axial falls back to progressive
  /// when it fails or flips).
  enum class SphereStart { automatic, progressive, axial };
  SphereStart sphere_start = SphereStart::automatic;
  // ---- step 3: harmonic interior
  /// Preconditioner of the harmonic solve's CG: jacobi, amg (vpm/amg.hpp) or automatic
  /// (vpm::choose_preconditioner).
  PreconditionerChoice preconditioner = PreconditionerChoice::automatic;
  double solver_tolerance = 1e-10;   ///< relative residual when an iterative solver is used
  // ---- step 4: untangling
  enum class Untangle { Never, IfFolded, Always };
  /// IfFolded: only when the harmonic map folded a tet. Always: also improve a fold-free map
  /// (lower distortion: docs/design.md 4.1).
  Untangle untangle = Untangle::IfFolded;
  UntangleOptions untangle_options{};   ///< theta = 1/128 by default
  /// Caps of the global run (the last resort before NumericalError), above those of
  /// untangle_options: harmonic maps of coiled or long-limbed shapes from a progressive sphere
  /// map start as tangled as min det J = -70 and needed 170-400 eps rounds of up to 300 L-BFGS
  /// iterations (docs/shapes.md). A map that converges sooner stops sooner.
  int global_untangle_max_outer_iterations = 200;
  int global_untangle_max_lbfgs_iterations = 300;
  /// IfFolded: first untangle locally (the folded tets and this many rings of neighbours free,
  /// boundary fixed, same energy and theta), then globally if folds remain. 0: global only.
  int local_untangle_rings = 3;
  /// UntangleOptions::stalled_sigma_min of those local runs (as in the volume map's local runs,
  /// untangle_local_options(); the global run keeps the paper's 0.1): a fold next to the fixed boundary of a large brain sat still for 38 outer iterations
  /// at 0.1 while eps fell 5 % a round (Colin27 at 383k tets: 6 folds, 12 s); docs/initial_map.md
  /// step 4.
  double local_untangle_sigma_min = 0.5;
  /// Step 5: rounds of refinement around folds left after step 4 (0: none).
  int max_refine_rounds = 3;
  /// Throw NumericalError when folds remain (the default and the contract of `vpm map`).
  /// false: return the folded map and let the caller read report.folds_after_untangle.
  bool throw_on_folds = true;
  /// Number of worst tets (smallest dihedral angle) listed in report.worst.
  int report_worst_tets = 5;
  /// Time budget (vpm/timing.hpp): every untangling run stops when it passes, and the conformal
  /// fallback and the refinement rounds are skipped after it; folds then left end in the
  /// NumericalError of throw_on_folds, which says the budget ran out.
  Deadline deadline{};
  /// Called with one line per step (progress display); may be empty.
  std::function<void(const std::string&)> progress;
};

/// What step 2 (the boundary to the sphere) did. Optional fields are absent when their step did
/// not run. area_distortion_* = mean over boundary triangles of |area ratio - 1| (areas
/// normalised).
struct SphereMapReport {
  int vertices = 0, faces = 0;                  ///< of the boundary surface
  std::string planar_weights = "cotangent";     ///< or "clamped cotangent" (second attempt)
  int flipped_after_conformal = 0;
  std::optional<int> flipped_after_south_pole;  ///< when the correction produced a map
  std::optional<bool> south_pole_correction;    ///< kept or not (when enabled)
  bool mirrored = false;                        ///< the map was reflected to face outwards
  double area_distortion_conformal = 0;
  // Moebius balancing (when enabled):
  std::optional<int> moebius_iterations;
  double moebius_centroid_norm = 0, area_distortion_balanced = 0;
  bool moebius_kept = false;
  std::optional<int> area_correction_steps;  ///< InitialMapOptions::area_correction
  // area equalisation (InitialMapOptions::sphere_density area): its target ("area"), the
  // flow's steps, the area-weighted mean square of log(sphere area / target) before and
  // after, the area distortion reached, kept or not
  std::string density_target;
  std::optional<int> density_steps;
  /// Where the equal-area steps were solved and why (vpm/placement.hpp; density_solve only).
  Placement placement;
  std::string density_solver;  ///< "cholmod-supernodal", "eigen-simplicial-ldlt" or "device-amg-cg" (the last step's)
  double density_misfit_before = 0, density_misfit_after = 0, area_distortion_density = 0;
  bool density_kept = false;
  // the progressive embedding (InitialMapOptions::sphere_start), when it ran: edge-collapse
  // passes, collapses, relaxation sweeps, seconds
  std::string start = "conformal";  ///< what the map started from: "conformal", "progressive" or "axial"
  std::optional<int> progressive_passes;
  int progressive_collapses = 0, progressive_sweeps = 0;
  double progressive_seconds = 0;
  double axial_seconds = 0;  ///< the axial map's seconds, when it was kept
  /// The automatic start's comparison, when the conformal start flipped or stayed crowded (its
  /// log misfit after the equalisation above kCrowdedMisfit) and the others were tried: each
  /// start's log misfit after its equalisation (absent: that start flipped or failed; `start`
  /// names the one kept, the smallest).
  std::optional<double> conformal_log_misfit, progressive_log_misfit, axial_log_misfit;
  /// Above this log misfit (area-weighted mean square of log(sphere area / target)) after the
  /// equalisation, the conformal start counts as crowded. Chosen on the development surfaces
  /// of docs/surfaces.md, which bound it: the folded AAL surface's conformal start leaves 0.003
  /// after the flow, the cartoon figure's 1.31 (limbs crushed; 0.034 from the progressive one).
  static constexpr double kCrowdedMisfit = 0.1;
  std::optional<int> flipped_before_repair;  ///< chord triangles facing inwards, repaired by
  std::optional<int> repair_steps;           ///< ... this many area-flow steps
  double area_distortion_final = 0;
  int flipped_triangles = 0;
  /// wall-clock seconds of the steps: the conformal map (with the south-pole correction and
  /// the orientation), the Moebius balancing, the area equalisation and, of it, its linear solves
  double seconds_conformal = 0, seconds_moebius = 0, seconds_density = 0, seconds_density_solve = 0;
};
/// {"vertices", "faces", "planar_weights", "flipped_after_conformal", "flipped_after_south_pole"?,
///  "south_pole_correction"?, "mirrored", "area_distortion_conformal", "moebius_iterations"?,
///  "moebius_centroid_norm"?, "area_distortion_balanced"?, "moebius_kept"?,
///  "area_correction_steps"?, "density"? {"target","steps","log_misfit_before",
///  "log_misfit_after","area_distortion","kept"}, "start", "conformal_log_misfit"?,
///  "progressive_log_misfit"?, "axial_log_misfit"?, "progressive"? {"passes","collapses",
///  "sweeps","seconds"}, "axial"? {"seconds"}, "flipped_before_repair"?, "repair_steps"?, "area_distortion_final",
///  "flipped_triangles", "timings_s" {"conformal","moebius","density","density_solve"}}
///  (? = only when present)
Json to_json(const SphereMapReport& report);

/// A tet of poor quality in the input.
struct WorstTet {
  int tet = -1;
  double min_dihedral_deg = 0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
};

/// One run of the untangler inside the initial map.
struct InitialUntangle {
  UntangleResult result;
  bool local = false;  ///< local (folded tets and `rings` rings free) or global
  int rings = 0;
};

/// What the initial map did, stage by stage.
struct InitialMapReport {
  std::string device;
  int input_vertices = 0, input_tets = 0;
  // input quality
  double min_dihedral_deg = 0;
  int min_dihedral_tet = -1;
  int tets_below_1deg = 0, tets_below_5deg = 0;
  std::vector<WorstTet> worst;  ///< InitialMapOptions::report_worst_tets smallest dihedral angles
  // step 1
  int split_rounds = 0, inserted_vertices = 0, four_boundary_tets_before = 0, four_boundary_tets_after = 0,
      centroid_splits = 0;
  int refined_vertices = 0, refined_tets = 0;
  SphereMapReport boundary;  ///< step 2
  // step 3
  bool harmonic_on_device = false;
  int harmonic_iterations = 0;
  double harmonic_relative_residual = 0;
  std::string harmonic_preconditioner = "jacobi";  ///< what InitialMapOptions::preconditioner resolved to
  int folds_before_untangle = 0;  ///< inverted tets of the harmonic map
  // step 4
  std::optional<InitialUntangle> untangle;              ///< the last untangling run
  std::optional<InitialUntangle> untangle_local_failed;  ///< a local run that left folds
  /// a local run (twice the rings) on the few folds a global run left; its result is kept
  /// only if it has fewer folds
  std::optional<InitialUntangle> untangle_cleanup;
  /// The last resort for at most 64 folds left: the boundary vertices near them free too, then
  /// put back on the sphere (inverted_after: the folds after that projection); the last attempt.
  std::optional<InitialUntangle> untangle_slide;
  int folds_after_untangle = 0;
  /// Set when steps 2-4 with the equal-area sphere map left a fold after local untangling and
  /// were redone with the conformal one (the report's other fields are of the redo), unless the
  /// redo crowded a part into a sliver of the ball (`crowded`): the first attempt is then kept
  /// and untangled globally (the report's other fields are of it).
  struct Fallback {
    std::string from;  ///< to_string(SphereDensity) of the first attempt
    int flipped_triangles = 0, folds_after_untangle = 0;
    double seconds = 0;  ///< spent on the first attempt's steps 2-4
    /// The conformal redo's smallest tet volume ratio (normalised) was below kCrowdedRatio.
    bool crowded = false;
    /// Decided from the conformal sphere map alone, before its interior and untangling: the
    /// boundary fixes an upper bound of every tet's ratio (the volume a tet on a boundary face
    /// can have inside the ball), and that bound was below kCrowdedRatio.
    bool crowded_by_boundary = false;
    /// that ratio (when crowded_by_boundary, its upper bound)
    double conformal_min_tet_ratio = 0;
    /// The automatic start chose the axial sphere map (SphereMapReport::start "axial"), which
    /// it keeps only where the conformal map flips or crowds the surface, so no conformal redo
    /// runs: the axial attempt is untangled globally from its local runs' result, as a crowded
    /// redo's is. (A start named in InitialMapOptions::sphere_start is redone from that start
    /// without the area flow.)
    bool axial = false;
  };
  /// A conformal map whose smallest normalised tet volume ratio is below this has squeezed a
  /// thin part (a long bone's shaft, a limb) into a sliver no round can restore.
  static constexpr double kCrowdedRatio = 1e-6;
  std::optional<Fallback> fallback;
  /// Set when step 5 ran (folds were left after step 4).
  struct Refine {
    int rounds = 0, inserted_vertices = 0, folds_before = 0, folds_after = 0;
    double seconds = 0;
  };
  std::optional<Refine> refine;
  double boundary_max_radius_error = 0;
  MapMetrics metrics;  ///< of the returned map against the refined input
  struct Timings {
    double input_quality = 0, metrics = 0, split = 0, boundary = 0, harmonic = 0, untangle = 0, total = 0;
  } timings;
};

/// {"device", "input": {"vertices","tets"}, "input_quality": {"min_dihedral_deg",
///  "min_dihedral_tet","tets_below_1deg","tets_below_5deg","worst": [{"tet","min_dihedral_deg",
///  "centroid"}], "warning"? (below 1 degree)}, "split": {"rounds","inserted_vertices",
///  "four_boundary_tets_before","four_boundary_tets_after","centroid_splits"},
///  "refined": {"vertices","tets"}, "boundary": to_json(SphereMapReport),
///  "harmonic": {"solver","preconditioner","iterations","relative_residual","inverted_tets"},
///  "folds_before_untangle", "untangle"? (to_json(UntangleResult) + "scope", "rings"),
///  "untangle_local_failed"?, "untangle_cleanup"?, "untangle_slide"?, "folds_after_untangle", "fallback"? {"from","to"
///  ("conformal", or "axial" for an automatic axial start's global run),"flipped_triangles",
///  "folds_after_untangle","seconds","crowded","crowded_by_boundary","conformal_min_tet_ratio","axial"}, "refine"? {"rounds",
///  "inserted_vertices","folds_before","folds_after","seconds"}, "boundary_max_radius_error",
///  "metrics": to_json(MapMetrics), "timings_s": {"input_quality","metrics","split","boundary",
///  "harmonic","untangle","total"}}
Json to_json(const InitialMapReport& report);

struct InitialMapResult {
  /// The refined mesh in input coordinates: input vertices first (input order), then the
  /// inserted ones; tets refined; input point fields carried (inserted vertices: mean of the
  /// edge ends, integer fields from the first end), input cell fields carried to the child
  /// tets, and point field `original_position` (n x 3) = position in the input mesh.
  TetMesh mesh;
  /// Same rows as mesh.vertices: positions in the closed unit ball, boundary vertices on the
  /// sphere (| |x| - 1 | <= 1e-12), every tet positively oriented (fold-free).
  Points ball;
  /// Boundary vertex mask of `mesh` (1 = on the sphere), n entries.
  std::vector<char> boundary;
  /// The Poisson solver of the harmonic step, built on mesh.tets and the map's device: the
  /// volume map reuses it (VolumeMapOptions::poisson) instead of building the Laplacian's
  /// pattern again. Drop it when not needed (it holds the pattern and device buffers).
  std::shared_ptr<PoissonSolver> poisson;
  InitialMapReport report;
};

/// An upper bound of the smallest normalised tet volume ratio (vpm/metrics.hpp) of any fold-free
/// map of `mesh` whose boundary vertices sit at their rows of `sphere` (on the unit sphere): the
/// tet on a boundary face f keeps at most area(f) * h / 3 of volume, its apex inside the ball at
/// most h = 1 + (the distance of f's plane from the origin) from that plane, and the ball
/// mesh's volume is the one its boundary encloses whatever the interior. The initial map's
/// conformal fallback asks it before building an interior: below
/// InitialMapReport::kCrowdedRatio no untangling can leave that boundary uncrowded.
double boundary_tet_ratio_bound(const TetMesh& mesh, const Points& sphere);

/// Maps `input` (validated tet mesh: positively oriented tets, boundary one closed genus-0
/// surface) to the unit ball; see above. Numerical work runs on `device` where a device
/// path exists (the harmonic solve); the result does not depend on the device beyond
/// round-off. Throws InputError for an input that is not a ball topologically, NumericalError
/// when the map cannot be made fold-free (unless options.throw_on_folds is false).
InitialMapResult initial_map(Device& device, const TetMesh& input, const InitialMapOptions& options = {});

// ---- the steps, exposed for tests, benchmarks and other stages --------------------------

/// "conformal", "area" (InitialMapOptions::SphereDensity); InputError otherwise.
InitialMapOptions::SphereDensity parse_sphere_density(const std::string& name);
const char* to_string(InitialMapOptions::SphereDensity d);
/// "auto", "progressive", "axial" (InitialMapOptions::SphereStart); InputError otherwise.
InitialMapOptions::SphereStart parse_sphere_start(const std::string& name);
/// "auto", "host" or "device" (InputError otherwise).
InitialMapOptions::DensitySolve parse_density_solve(const std::string& name);

/// Result of step 1.
struct SplitResult {
  TetMesh mesh;                 ///< refined mesh (input vertices first), fields carried
  std::vector<int> parent_tet;  ///< for each refined tet, the input tet it lies in
  /// For each refined vertex: the two input-or-earlier vertices whose midpoint it is
  /// ({v, v} for input vertices; {a, b} with a, b < v, or {-1, -1} for a centroid).
  std::vector<std::array<int, 2>> parents;
  /// boundary_faces(mesh.tets): the input's boundary triangles, which the splits do not change
  /// (they insert interior vertices; each split tet keeps its boundary face at the same corner).
  Triangles boundary;
  int rounds = 0;
  int inserted_vertices = 0;
  int four_boundary_tets_before = 0;
  int four_boundary_tets_after = 0;
  int centroid_splits = 0;
};
/// Step 1 on `input` (positively oriented tets).
SplitResult split_boundary_edges(const TetMesh& input, int max_rounds = 4);
/// The same, given `boundary` = boundary_faces(input.tets) (the caller has it already).
SplitResult split_boundary_edges(const TetMesh& input, const Triangles& boundary, int max_rounds = 4);

/// Step 5's refinement: every interior edge (not on the boundary surface `boundary`) of the
/// tets within `rings` vertex rings of `seed_tets` split at its midpoint, as
/// split_boundary_edges does (point fields averaged, so a field of positions in another space
/// comes out at the midpoints there too). The boundary surface is unchanged.
SplitResult split_edges_near(const TetMesh& mesh, const Triangles& boundary, const std::vector<int>& seed_tets,
                             int rings);

/// Number of tets whose four vertices are all boundary vertices.
int count_four_boundary_tets(const Tets& tets, const std::vector<char>& boundary);

/// Result of step 2.
struct SphereMapResult {
  Points sphere;       ///< k x 3 unit vectors, one per surface vertex (rows of `vertices`)
  int flipped_triangles = 0;
  SphereMapReport report;
};
/// Step 2 for a closed genus-0 triangle surface with outward orientation (vertices unused by
/// a triangle are mapped to (0,0,1) and ignored). Throws InputError if not genus 0.
SphereMapResult sphere_map(const TriSurface& surface, const InitialMapOptions& options = {});
/// The same; `device` (may be null: host) is where InitialMapOptions::density_solve may run.
SphereMapResult sphere_map(const TriSurface& surface, const InitialMapOptions& options, Device* device);

/// Mean over `triangles` of |a_sphere/A_sphere / (a_in/A_in) - 1|.
double area_distortion(const Points& input, const Points& sphere, const Triangles& triangles);
/// Number of triangles with det(a, b, c) <= 0 (inward-facing on the sphere).
int flipped_sphere_triangles(const Points& sphere, const Triangles& triangles);

}  // namespace vpm
