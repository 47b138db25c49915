#pragma once
// The area-preserving map of a closed genus-0 triangle surface to the unit sphere, and of a
// disk-like one (one boundary loop) to the unit disk: the paper's method one dimension down
// (docs/surfaces.md).
//
// To the sphere:
//  1. sphere map (vpm::sphere_map, the initial map's step 2 for a tet mesh's boundary): the
//     spherical conformal map, Moebius balancing, then the compressible flow on the sphere that
//     equalises each vertex's share of the area (a log-density Moser flow, map/sphere_density);
//     flip-free by construction, a progressive embedding where the conformal map of long tubes
//     underflows.
//  2. polish of the face areas: Gauss-Newton steps on the chord triangles' areas against the
//     input's, min over tangent moves dx of sum_f (1 - A_f(x + dx) / t_f)^2 linearised and solved
//     by early-stopped CGLS from dx = 0 (the same iteration as the tet polish, map/polish_cgls),
//     each step put back on the sphere, halved while it flips a face, kept only while it lowers
//     the face distortion.
//
// To the disk: faces with all three corners on the boundary loop ("ears") split first (one of
// their interior edges halved: on the circle such a face spans about the cube of its corners'
// spacing, far below its share, whatever the map), then the boundary loop on the unit circle at
// angles proportional to its arc length,
// the interior by Floater's mean value coordinates (a convex combination of its neighbours,
// fold-free by Tutte's theorem), then the same polish, interior vertices moving in the plane
// and boundary vertices along the circle.
//
// The face area ratio of face f is (A_f / sum A) / (A0_f / sum A0), with A the chord (flat)
// triangle areas on the sphere (or the triangles' in the disk) and A0 the input's; a face is
// flipped when its chord triangle faces the centre (det(a, b, c) <= 0), in the disk when it
// turns clockwise. The maps never return a flipped face.
#include <Eigen/Core>
#include <array>
#include <functional>
#include <string>
#include <vector>

#include "vpm/initial_map.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/metrics.hpp"
#include "vpm/timing.hpp"

namespace vpm {

class Device;

/// Where a surface is mapped: closed genus-0 surfaces to the unit sphere, surfaces with one
/// boundary loop (a disk topologically) to the unit disk in the plane z = 0.
enum class SurfaceDomain { sphere, disk };
const char* to_string(SurfaceDomain domain);

struct SurfaceMapOptions {
  /// Stop polishing once the face area mean |r - 1| is at most this.
  double tolerance = 0.005;
  /// At most this many polish steps (0: the sphere map alone).
  int polish_rounds = 200;
  /// CGLS iterations per polish step.
  int polish_iterations = 60;
  /// Steps end once the last five lowered the face area mean |r - 1| by less than five times
  /// this fraction of it, or one step gained nothing (discarded).
  double polish_min_gain = 0.002;
  /// The sphere map's options (its `sphere_density`, `sphere_start`, `density_*`, the conformal
  /// and balancing steps); the tet-specific fields are ignored.
  InitialMapOptions sphere{};
  Deadline deadline{};  ///< checked before every polish step
  /// Disk maps: split each ear (a face whose three corners are on the boundary loop) by halving
  /// its longest interior edge before the map, the new vertices appended after the input's
  /// (SurfaceMapResult::added). False maps the input's faces as they are, and its ears stay
  /// crushed (the map then misses a tolerance near 0.5 % wherever a cut left ears).
  bool split_ears = true;
  /// Called with one line per step (progress display); may be empty.
  std::function<void(const std::string&)> progress;
};

/// One polish step (a "round" of the report, kind "polish").
struct SurfaceMapStep {
  double face_mean_abs_dev = 0;  ///< after the step (or before it, when discarded)
  int solver_iterations = 0;
  double solver_residual = 0;
  double step = 1;               ///< the fraction of the CGLS direction taken (halved on flips)
  int frozen_vertices = 0;       ///< vertices the step held still because their faces flipped in a trial
  bool discarded = false;
  double seconds = 0;
};

/// The map's area metrics against the input (docs/design.md 5 one dimension down; both surfaces
/// normalised to total area 1, a vertex's dual area a third of its faces' areas).
struct SurfaceMetrics {
  int flipped_faces = 0;           ///< chord triangles facing the centre
  RatioStats face_area_ratio;      ///< normalised face area ratios
  RatioStats vertex_area_ratio;    ///< normalised dual area ratios
  double max_radius_error = 0;     ///< max | |x| - 1 |
  Eigen::VectorXd face_ratio;      ///< per-face ratios (length faces)
  Eigen::VectorXd vertex_ratio;    ///< per-vertex ratios (length vertices)
};
/// Metrics of `mapped` (n x 3 on the unit sphere, or in the unit disk) against `reference` (the
/// input), same faces; max_radius_error over all points (sphere) or the boundary loop's (disk).
SurfaceMetrics surface_metrics(const Points& reference, const Points& mapped, const Triangles& faces,
                               SurfaceDomain domain = SurfaceDomain::sphere);
/// {"flipped_faces", "face_area_ratio": to_json(RatioStats), "vertex_area_ratio": ...,
///  "max_radius_error"}
Json to_json(const SurfaceMetrics& metrics);

struct SurfaceMapReport {
  SurfaceDomain domain = SurfaceDomain::sphere;
  int vertices = 0, faces = 0;
  int boundary_vertices = 0;                ///< disk: the boundary loop's
  /// disk: faces with all three corners on the boundary loop. On the circle such a face's area
  /// is about the cube of its corners' spacing, far below its share: these maps miss the
  /// tolerance (docs/surfaces.md).
  int ears = 0;
  int split_edges = 0;                      ///< disk: interior edges halved to remove the ears
  bool reversed = false;                    ///< the input's faces pointed inwards (mapped reversed)
  SphereMapReport sphere;                   ///< step 1 (sphere)
  SurfaceMetrics initial;                   ///< after step 1
  std::vector<SurfaceMapStep> polish;       ///< step 2
  /// "tolerance", "rounds", "stalled", "time_budget", or "none" (polish_rounds 0)
  std::string stop_reason = "none";
  bool converged = false;                   ///< face area mean |r - 1| <= tolerance
  double tolerance = 0;
  SurfaceMetrics final;                     ///< of the returned map
  double seconds_sphere_map = 0, seconds_polish = 0, seconds_total = 0;  ///< step 1 (or the disk embedding), 2, all
};
/// {"domain": "sphere"|"disk", "input": {"vertices","faces","reversed"}, "initial":
///  to_json(SurfaceMetrics) (after the sphere map or the disk embedding), "final": the same (the returned map), "rounds": [{"round","kind": "polish",
///  "face_mean_abs_dev","solver_iterations","solver_residual","step_fraction","frozen_vertices",
///  "discarded","seconds"}], "sphere_map": to_json(SphereMapReport) (sphere) or "disk_map":
///  {"boundary_vertices","ears","weights": "mean value"} (disk), "stop_reason",
///  "converged", "convergence": {"tolerance","reached","converged"},
///  "timings_s": {"sphere_map" (or "disk_map"),"polish","total"}}
Json to_json(const SurfaceMapReport& report);

struct SurfaceMapResult {
  /// On the unit sphere, or in the unit disk (z = 0, the boundary loop on the unit circle): the
  /// input's n rows, then one row per vertex added by splitting ears (`added`)
  Points sphere;
  /// The mapped faces when ears were split (indices into `sphere`); empty: the input's faces
  Triangles faces;
  /// Per added vertex n + i, the two input vertices whose edge it halves
  std::vector<std::array<int, 2>> added;
  SurfaceMapReport report;
};

/// A per-vertex field of the input (n rows) carried to the mapped surface's vertices: each added
/// vertex (SurfaceMapResult::added) gets the mean of its edge's two ends (the midpoint, for
/// positions). Throws InputError when `values` does not have the input's n rows.
FieldValues extend_to_mapped(const FieldValues& values, const SurfaceMapResult& result);

/// The faces of `result.sphere`: result.faces when ears were split, else `input_faces`.
const Triangles& mapped_faces(const Triangles& input_faces, const SurfaceMapResult& result);

/// Checks that `surface` is one closed, manifold, genus-0 surface with consistently oriented
/// faces; throws InputError naming `what` and the first problem (an open or non-manifold edge, a
/// non-manifold vertex, the genus, the number of components) otherwise.
void validate_closed_surface(const TriSurface& surface, const std::string& what);

/// Checks that `surface` is one manifold, consistently oriented surface with exactly one boundary
/// loop and Euler characteristic 1 (a disk topologically), every vertex in a face, every face
/// with an area; InputError naming `what` and the first problem otherwise.
void validate_disk_surface(const TriSurface& surface, const std::string& what);

/// sphere for a surface without open edges, disk otherwise (the matching validate_* then says
/// whether it is one).
SurfaceDomain surface_domain(const TriSurface& surface);

/// Maps `surface` (validate_disk_surface) to the unit disk; see above (its ears split first
/// unless options.split_ears is false). Throws InputError for a surface that is not a disk
/// topologically.
SurfaceMapResult map_to_disk(const TriSurface& surface, const SurfaceMapOptions& options = {});

/// Maps `surface` (validate_closed_surface) to the unit sphere; see above. `device` (may be
/// null: the host) is where the sphere map's equal-area steps may be solved
/// (InitialMapOptions::density_solve). Throws InputError for a surface that is not one closed
/// genus-0 surface, NumericalError when the sphere map flips faces it cannot repair.
SurfaceMapResult map_to_sphere(const TriSurface& surface, const SurfaceMapOptions& options = {},
                               Device* device = nullptr);

}  // namespace vpm
