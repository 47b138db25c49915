#pragma once
// The volume-preserving map inside the unit ball (paper sections 3, 4.2, 4.3; docs/design.md 4.1
// steps 5-6 and 4.2): starting from a fold-free map of a tet mesh to the ball, move the
// vertices until every vertex's dual volume is its input dual volume (both normalised to the
// total volume).
//
// Moser rounds on a fixed field. Per round, on the current ball mesh
// ("background"): dual volumes V_i, targets m_i = input dual volumes rescaled to the current
// total volume, rho0 = m / V; one Neumann solve  -K psi = V - m  (K: the cotangent stiffness
// of vpm/laplacian.hpp, negative semi-definite, so this is  K psi = m - V); per-tet gradients
// of psi (paper eq. 12), volume-weighted vertex averages (eq. 13), normal component removed
// at boundary vertices. The field v(y, t) = grad psi(y) / ((1 - t) rho0(y) + t) (grad psi and
// rho0 interpolated barycentrically at y in the background mesh) carries density rho0 to the
// uniform one (continuity equation d rho/dt + div(rho v) = 0). Every vertex follows its
// pathline from t = 0 to 1 with RK4; boundary vertices slide on the sphere (their velocity's
// normal part is removed and they are renormalised to radius 1 after each stage) or stay
// fixed. Point location + interpolation run as OpenCL kernels (kernels/moser.cl: walk through
// tet faces from the previous containing tet, uniform-grid fallback, clamping to the nearest
// boundary tet for points just outside the inscribed polyhedron) or as the same code on the
// host. Then polish rounds (VolumeMapOptions::polish_rounds): Gauss-Newton steps on the
// per-tet volumes (CGLS, minimum-norm), which remove the per-tet distortion that the
// vertex-based rounds leave (docs/volume_map.md).
// The paper's own loop and vsem, its peers, run through volume_map_peer
// (vpm/volume_map_peers.hpp) for comparison.
//
// Fold safety (every round): after each round the tets with signed volume <= 0 are counted;
// if any, they are untangled locally (vpm::untangle_local, theta = 0.5, two rings, boundary
// fixed); if that fails the round is redone on a shorter time interval (t_end halved, up to
// `max_step_halvings` times); if it still folds the round is discarded, the previous fold-free
// map kept and the iteration stops (reported). An input map that is folded and cannot be
// untangled is NumericalError. The returned map is always fold-free.
#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "vpm/placement.hpp"
#include "vpm/solver.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/metrics.hpp"
#include "vpm/timing.hpp"

namespace vpm {

class Device;
class PoissonSolver;

enum class MapBoundary {
  automatic,  ///< slide (fixed for the peers, their published behaviour; vpm/volume_map_peers.hpp)
  slide,      ///< boundary vertices move tangentially on the unit sphere
  fixed,      ///< boundary vertices do not move
};
/// "auto", "slide", "fixed" (InputError otherwise).
MapBoundary parse_map_boundary(const std::string& name);
const char* to_string(MapBoundary m);


struct VolumeMapOptions {
  /// Rounds to run (Moser rounds; a peer's: paper: explicit steps; vsem: fixed-point iterations).
  /// -1: until the vertex mean |r - 1| <= tolerance or max_rounds is reached.
  int rounds = -1;
  /// Cap used when rounds == -1: 8 for the Moser rounds (the paper's loop: its steps; vsem 15) when <= 0.
  int max_rounds = 0;
  /// Stop when the vertex mean |r - 1| (normalised dual volumes) is at or below this.
  double tolerance = 0.01;
  /// RK4 steps per Moser round (t from 0 to 1): 10 give the same maps as 40 to 3-4 digits on
  /// brains and on the shapes benchmark at a quarter of the advection's time (docs/volume_map.md).
  int rk_steps = 10;
  MapBoundary boundary = MapBoundary::automatic;
  /// Linear solver: cg (preconditioned CG) or paper (BiCGSTAB on the normal equations);
  /// bicgstab is refused (InputError).
  SolverMethod solver = SolverMethod::cg;
  /// Preconditioner of cg: jacobi, amg (smoothed aggregation, vpm/amg.hpp; the hierarchy is
  /// built once and its values refreshed every solve) or automatic: AMG on CPU devices from 600k
  /// tets on (vpm::kAutoAmgTets), else Jacobi (vpm::choose_preconditioner).
  PreconditionerChoice preconditioner = PreconditionerChoice::automatic;
  /// Relative residual of each linear solve.
  double solver_tolerance = 1e-8;
  /// Local untangling (theta 0.5, two rings, boundary fixed) of rounds that fold.
  bool local_untangle = true;
  /// Times a folding round is redone with t_end halved before it is discarded.
  int max_step_halvings = 3;
  /// Polish rounds after the Moser rounds (not for the peers): Gauss-Newton steps on the
  /// per-tet volumes, min over dx of sum_t (1 - V_t(x + dx) / m_t)^2 linearised, solved by
  /// `polish_iterations` CGLS iterations from dx = 0 (minimum-norm, early-stopped), boundary
  /// vertices moving tangentially (slide) or not at all (fixed); x += dx, halved while it folds.
  /// They target the per-tet distortion that vertex-based Moser rounds cannot see.
  /// At most this many (they stop when the tet mean |r-1| improves by less than
  /// `polish_min_gain`, or by less than 3 % once the vertex mean |r-1| is within `tolerance`
  /// (not in polish_volumes, vpm/polish.hpp): the last rounds of large meshes gain 0-1.5 % each
  /// for seconds, docs/volume_map.md). With
  /// rounds == -1 the Moser rounds hand over to the polish once the vertex mean |r-1| is within
  /// 5 x tolerance, or a round gains less than a fifth on it (stop_reason "stalled"). A polish
  /// step that folds is untangled locally like a round, then halved. Short of the tolerance,
  /// the polish goes on past this count while each round still lowers the tet mean |r-1| by a
  /// tenth, up to 4 x this count (long thin parts gain that much a round well past the eighth).
  int polish_rounds = 8;
  int polish_iterations = 60;
  /// The fraction by which a polish round must lower the tet mean |r-1| for another to follow.
  double polish_min_gain = 0.01;
  /// The polish's CGLS iterations when the polish starts with the vertex mean |r-1| above 5 x
  /// `tolerance` (the Moser rounds stalled far from it, as on a hand's fingers; docs/shapes.md),
  /// at up to 30,000 tets, times cbrt(tets / 30,000) above (the same correction spans more
  /// elements on a finer mesh, vpm::polish_iterations_for); otherwise `polish_iterations`.
  int polish_iterations_far = 200;
  /// Where the RK4 advection (point location and field interpolation) runs: automatic = on
  /// the OpenCL device when there is one (kernels/moser.cl), else the host reference. The
  /// field's vertex gradients (eq. 12-13) are computed next to it on GPUs, or with `device`;
  /// with automatic on a CPU device they stay on the host (as fast there, and the maps of
  /// fragile shapes keep the host's round-off: docs/volume_map.md).
  ExecutionPlace advection = ExecutionPlace::automatic;
  /// Where the polish's CGLS runs: automatic = the OpenCL kernels (kernels/polish.cl) on GPUs,
  /// the threaded host loops otherwise (on PoCL the kernels are slower than the host loops:
  /// docs/volume_map.md).
  ExecutionPlace polish = ExecutionPlace::automatic;
  /// Called with one line per round (progress display); may be empty.
  std::function<void(const std::string&)> progress;
  /// Time budget (vpm/timing.hpp): checked before every Moser and polish round; when it has
  /// passed the rounds stop with the map reached so far (stop_reason "time_budget").
  Deadline deadline{};
  /// A Poisson solver already built on these tets and this device (InitialMapResult::poisson):
  /// the Moser solves reuse it instead of building the Laplacian's pattern again, with the
  /// solver options above. Ignored when it was built on other tets or another
  /// device; nullptr: one is built.
  std::shared_ptr<PoissonSolver> poisson;
};

/// One round (Moser round, paper step or vsem iteration).
struct VolumeMapRound {
  int round = 0;                  ///< 1-based
  std::string kind = "moser";     ///< "moser", "paper", "vsem" or "polish"
  double vertex_mean_abs_dev = 0; ///< after the round (normalised dual volume ratios vs input)
  double tet_mean_abs_dev = 0;    ///< after the round (normalised tet volume ratios vs input)
  int folds_before_untangle = 0;  ///< tets with signed volume <= 0 right after advection
  int folds = 0;                  ///< after local untangling (0 unless the round was discarded)
  bool untangled = false;         ///< local untangling ran
  bool discarded = false;         ///< the round could not be made fold-free and was undone
  double t_end = 1;               ///< integration interval used (halved on retries), or dt (paper)
  int solver_iterations = 0;
  double solver_residual = 0;
  // Point location statistics (moser): walk steps per location, grid fallbacks, clamped points.
  double walk_steps_per_location = 0;
  long long grid_fallbacks = 0;
  long long clamped = 0;
  // Seconds.
  double time_solve = 0, time_field = 0, time_advect = 0, time_untangle = 0, time_total = 0;
};

/// {"round", "kind", "vertex_mean_abs_dev", "tet_mean_abs_dev", "folds_before_untangle",
///  "folds", "untangled", "discarded", "t_end", "solver_iterations", "solver_residual",
///  "walk_steps_per_location", "grid_fallbacks", "clamped",
///  "timings_s": {"solve", "field", "advect", "untangle", "total"}}
Json to_json(const VolumeMapRound& round);

/// Seconds spent in the parts of a volume map, summed over its rounds.
struct VolumeMapTimings {
  double solve = 0, field = 0, advect = 0, untangle = 0, total = 0;
};

struct VolumeMapResult {
  std::vector<VolumeMapRound> rounds;
  double initial_vertex_mean_abs_dev = 0, initial_tet_mean_abs_dev = 0;
  double final_vertex_mean_abs_dev = 0, final_tet_mean_abs_dev = 0;
  int final_folds = 0;     ///< always 0 on return
  /// of the Moser rounds: "tolerance", "rounds", "stalled", "fold"; "polish_only" from
  /// polish_volumes (vpm/polish.hpp); "time_budget"
  /// when VolumeMapOptions::deadline stopped the Moser or polish rounds
  std::string stop_reason;
  // What ran:
  std::string method = "moser";  ///< the rounds that ran: "moser", or a peer's ("paper", "vsem")
  bool slide = true;          ///< boundary vertices slid on the sphere (else fixed)
  std::string solver = "cg";  ///< VolumeMapOptions::solver
  std::string preconditioner = "jacobi";  ///< what VolumeMapOptions::preconditioner resolved to
  int rk_steps = 10;
  bool device_advection = false;  ///< the advection ran on the OpenCL device
  /// Where the advection, the field's gradients and the polish ran, and why (vpm/placement.hpp).
  Placement placement;
  VolumeMapTimings timings;
};

/// {"method", "boundary", "solver", "preconditioner", "rk_steps", "advection",
///  "initial": {"vertex_mean_abs_dev", "tet_mean_abs_dev"},
///  "final": {"vertex_mean_abs_dev", "tet_mean_abs_dev", "inverted_tets"}, "stop_reason",
///  "rounds": [to_json(round)...], "timings_s": {"solve", "field", "advect", "untangle", "total"}}
Json to_json(const VolumeMapResult& result);

/// Maps `ball` (n x 3; in: a fold-free map of the mesh to the closed unit ball with boundary
/// vertices on the sphere; out: the volume-preserving map) of the mesh (`reference` n x 3, the
/// input coordinates, any unit; `tets` m x 4, positively oriented on `reference`). Boundary
/// vertices are those of the mesh's boundary faces. Runs on `device` (OpenCL kernels for point
/// location and RK stages, solver on the device; host: the Eigen/C++ reference).
/// Throws InputError on inconsistent sizes, NumericalError when the input map is folded and
/// cannot be untangled or a linear solve fails (the message says what was reached); on
/// NumericalError `ball` holds the last fold-free map (or the input if none).
VolumeMapResult volume_preserving_map(Device& device, const Points& reference, const Tets& tets,
                                      Points& ball, const VolumeMapOptions& options = {});

}  // namespace vpm
