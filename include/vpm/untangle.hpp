#pragma once
// Fold removal for tet maps: Garanzha, Kaporin, Kudryavtseva, Protais, Ray & Sokolov,
// "Foldover-free maps in 50 lines of code", ACM TOG 40(4), 2021 (docs/design.md 4.1 steps 4 and 6).
//
// A map is given by new positions `x` of the vertices of a reference mesh (`reference`,
// `tets`). For each tet t, J_t is the Jacobian of the affine map reference tet -> mapped tet
// (3 x 3, J = X R^-1 with X, R the edge matrices [v1-v0, v2-v0, v3-v0]) and D_t = det J_t.
// The minimised energy is
//
//   E(x) = sum_t w_t [ (1 - theta) tr(J^T J) / chi(D, eps)^(2/3) + theta (D^2 + 1) / chi(D, eps) ]
//   chi(D, eps) = (D + sqrt(eps^2 + D^2)) / 2          (> 0 for every D; stable form for D < 0)
//
// with w_t the reference volume of tet t (normalised to sum 1). The first term measures shape
// distortion (minimal for a similarity), the second volume distortion (minimal at D = 1), so
// the reference should have the same total volume as the map: by default the reference is
// rescaled to the total signed volume of `x` (UntangleOptions::rescale_reference).
// Each outer iteration minimises E with L-BFGS over the free vertices at fixed eps, then
// updates eps = 2 sqrt(mu (mu - Dmin)), mu = (1 - sigma) chi(Dmin, eps),
// sigma = max(1 - E/E_prev, 0.1) while Dmin < mu (else eps = 1e-10; a stalled fold may take a
// larger floor, UntangleOptions::stalled_sigma_min): eps shrinks as the folds clear, so the
// barrier at D = 0 takes hold only when all D can be made positive.
//
// Host implementation (Eigen; the energy and gradient over a pool of host threads, one per 512
// active tets at most the hardware's, with the one-thread result bit for bit whatever their
// number); the per-tet energy and gradient can also be evaluated on an OpenCL device (overloads
// taking a Device).
#include <string>
#include <vector>

#include "vpm/error.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

class Device;

struct UntangleOptions {
  /// Weight of the volume term (theta): 1/128 for the global untangle after the harmonic map
  /// (shape first), 0.5 for the local untangle between Moser rounds (keep volumes).
  double theta = 1.0 / 128.0;
  /// Outer iterations (eps updates). Each runs one L-BFGS minimisation.
  int max_outer_iterations = 50;
  /// Smallest sigma of the eps update after an outer iteration that left a fold stalled (Dmin
  /// <= 0 and raised by under a tenth of |Dmin|); otherwise the paper's 0.1. The default, 0.1,
  /// is the paper's schedule throughout; larger values shrink eps faster past a fold that sits
  /// still (InitialMapOptions::local_untangle_sigma_min, untangle_local_options()).
  double stalled_sigma_min = 0.1;
  /// L-BFGS iterations per outer iteration.
  int max_lbfgs_iterations = 100;
  /// L-BFGS memory (number of correction pairs).
  int lbfgs_memory = 8;
  /// L-BFGS stops when |grad|_inf <= gradient_tolerance * (1 + |grad_0|_inf)
  /// or the relative energy change falls below energy_tolerance.
  double gradient_tolerance = 1e-6;
  double energy_tolerance = 1e-7;
  /// Stop the outer loop when no tet is inverted and the relative energy change of the last
  /// outer iteration is below this (the paper's 1e-5).
  double outer_energy_tolerance = 1e-5;
  /// Stop as soon as no tet is inverted (minimum quality work), instead of also converging the
  /// energy. Off by default: the further descent improves the map (docs/design.md 4.1 table).
  bool stop_when_untangled = false;
  /// Wall-clock budget in seconds (0: none). Checked between L-BFGS iterations; when it runs
  /// out the current positions are returned (folds are still reported, never hidden).
  double max_seconds = 0;
  /// Scale the reference so its total volume equals the total signed volume of x.
  bool rescale_reference = true;
};

struct UntangleResult {
  int inverted_before = 0;   ///< tets of the whole mesh with signed volume <= 0 before
  int inverted_after = 0;    ///< same, after
  int iterations = 0;        ///< outer iterations (eps updates) run
  int lbfgs_iterations = 0;  ///< total L-BFGS iterations
  int evaluations = 0;       ///< total energy + gradient evaluations
  int free_vertices = 0;     ///< vertices that were allowed to move
  int active_tets = 0;       ///< tets whose energy was minimised
  double min_det_before = 0; ///< smallest det J before (relative to the rescaled reference)
  double min_det_after = 0;  ///< smallest det J after
  double energy_before = 0;  ///< energy at the start (first eps)
  double energy_after = 0;   ///< energy at the end (last eps)
  double final_eps = 0;
  double seconds = 0;
  bool out_of_time = false;  ///< stopped by options.max_seconds
  /// The minimisation ended with more inverted tets than it started with, so `x` was left as
  /// given (inverted_after == inverted_before): the untangler never returns more folds.
  bool kept_input = false;
  std::vector<int> inverted_tets;  ///< indices (into `tets`) of all tets still inverted after
};
/// The scalar fields above (same names), plus "inverted_tets_first": the first 20 inverted tets.
Json to_json(const UntangleResult& result);

/// Untangles the map `x` (n x 3, updated in place) of the mesh (`reference`, n x 3;
/// `tets`, m x 4 positively oriented on `reference`), moving only vertices with
/// fixed[v] == 0 (`fixed` has n entries; typically the boundary vertices are fixed).
/// Minimises the energy above over all tets. Never throws for remaining folds: check
/// `inverted_after` (and `inverted_tets`). Throws InputError on inconsistent sizes.
UntangleResult untangle(const Points& reference, const Tets& tets, Points& x,
                        const std::vector<char>& fixed, const UntangleOptions& options = {});

/// Options of the local untangle between Moser and polish rounds (and of the sphere map's and
/// the registration check's local runs): theta = 0.5, and stalled_sigma_min = 0.5 so that a
/// fold an eps round hardly moved does not hold eps near its value for tens of rounds.
UntangleOptions untangle_local_options();

/// Local variant (docs/design.md 4.1 step 6): frees only the vertices of `folded` (tet indices)
/// and `rings` rings of neighbours around them (vertices sharing a tet), except those with
/// fixed[v] != 0, and minimises the energy over the tets touching a free vertex.
/// Use with options.theta = 0.5 (see untangle_local_options()). `folded` empty: nothing to do.
/// The rescaled reference uses the volume of the active tets only.
UntangleResult untangle_local(const Points& reference, const Tets& tets, Points& x,
                              const std::vector<char>& fixed, const std::vector<int>& folded,
                              int rings = 2, const UntangleOptions& options = untangle_local_options());

/// Boundary triangles flipped on the unit sphere: indices f of `faces` (k x 3, outward
/// boundary triangles of a ball mesh) with det[x_a, x_b, x_c] <= 0.
std::vector<int> flipped_sphere_faces(const Triangles& faces, const Points& x);

/// Repairs boundary triangles flipped on the unit sphere by moving vertices along the sphere
/// only. A tet standing on such a face cannot be untangled with the boundary fixed (its apex
/// would have to leave the ball), so this runs first: the cones (O, a, b, c) over `faces`, with
/// one fixed apex each at the centre, are untangled by untangle_local (the flipped cones'
/// vertices and 2, then 4, rings free; only face vertices can move) against `reference`
/// (n x 3, a fold-free configuration such as the positions before the step that flipped them);
/// the face vertices are then put back on the sphere, which keeps the sign of det[a, b, c].
/// `x` (n x 3, in/out): only vertices of `faces` change, and none with pinned[v] != 0 (`pinned`
/// n entries or empty). Returns the flipped faces left.
int unflip_sphere_faces(const Points& reference, const Triangles& faces, Points& x,
                        const std::vector<char>& pinned = {});

/// Same, with the per-tet energy and gradient evaluated on `device` (kernels/untangle.cl) when
/// it is an OpenCL device; the L-BFGS iterations stay on the host. Results agree with the host
/// version to round-off (energies are summed in the same order on the host).
UntangleResult untangle(Device& device, const Points& reference, const Tets& tets, Points& x,
                        const std::vector<char>& fixed, const UntangleOptions& options = {});
UntangleResult untangle_local(Device& device, const Points& reference, const Tets& tets, Points& x,
                              const std::vector<char>& fixed, const std::vector<int>& folded,
                              int rings = 2, const UntangleOptions& options = untangle_local_options());

/// Indices of tets of `tets` with signed volume <= 0 at positions `x`.
std::vector<int> inverted_tets(const Points& x, const Tets& tets);

}  // namespace vpm
