#pragma once
// Private: step 4 of the initial map (vpm/initial_map.hpp), the untangling of the harmonic map.
#include <vector>

#include "vpm/initial_map.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// Folds left by the global run up to which a local cleanup (and then the sliding one) is tried.
constexpr int kCleanupMaxFolds = 64;

/// InitialMapOptions::untangle on `ball` (boundary fixed): locally first when only folds are to
/// be repaired (rings, then 2x and 4x the rings around what is left, while each run leaves
/// fewer folds), globally if folds remain (InitialMapOptions::global_untangle_max_*), then
/// locally again with twice the rings if the global run left at most kCleanupMaxFolds, and for
/// what is still left (at most kCleanupMaxFolds) with the boundary vertices of the folded tets
/// sliding on the sphere. Fills rep.untangle*, starts from rep.folds_before_untangle; returns
/// the folds left. `global` false skips the global run that would follow local runs leaving
/// folds, and its cleanup (the sliding still runs), for an attempt with a cheaper fallback:
/// initial_map's equal-area boundary, whose fallback is the conformal one (the global run over
/// a 213k-tet brain took 40-90 s and still left a fold on 3 of 60 cohort brains, the conformal
/// attempt 0.3 s); `ball` then keeps the local runs' fewest folds. Untangle::Always runs
/// globally whatever `global` says. `local_tried`: `ball` is such a local result, the last run
/// in rep.untangle, so the global run follows at once, from it (the initial map's return to
/// its equal-area attempt after a crowded fallback).
int untangle_map(Device& device, const TetMesh& m, const std::vector<char>& boundary, const InitialMapOptions& opt,
                 Points& ball, InitialMapReport& rep, bool global = true, bool local_tried = false);

/// Step 5 (vpm/initial_map.hpp): while folds remain, up to opt.max_refine_rounds times, the
/// interior edges of the tets within 1, 2, 4 rings of the folds split (split_edges_near) and
/// untangle_map run again on the refined mesh; a round that leaves as many folds is dropped and
/// ends the step. Updates res.mesh, res.ball, res.boundary (not res.poisson), rep.refine,
/// rep.folds_after_untangle and rep.refined_*; true when it kept a refined mesh.
bool refine_folds(Device& device, const Triangles& boundary_faces, const InitialMapOptions& opt,
                  InitialMapResult& res, InitialMapReport& rep);

}  // namespace vpm::detail
