#pragma once
// Area-preserving landmark registration on the unit sphere: the two-dimensional form of the
// ball's registration (vpm/registration.hpp, paper section 5), for surfaces mapped to the
// sphere by vpm::map_to_sphere.
//
// 1. Rigid step: the rotation that best maps the landmarks onto the targets (Kabsch,
//    vpm::kabsch_rotation), applied to every vertex.
// 2. Pathlines: each landmark p travels to its target q along the great circle,
//    x(t) = slerp(p, q, t), at constant angular speed.
// 3. Field: at each RK4 stage time t the velocity is the surface-divergence-free interpolant of
//    the samples (x_i(t), x_i'(t)): v(x) = x × sum_j H(x, y_j) u_j, H the mixed Hessian
//    grad_x grad_y^T of the Gaussian exp(-lambda |x - y|^2), u_j tangent at y_j. A field
//    v(x) = x × w(x) is tangent to every sphere about the centre, and x × grad psi has zero
//    surface divergence: the continuous motion keeps every area.
// 4. Advection: every vertex moves with K RK4 steps (the flow keeps |x|, the result is put back
//    on the sphere against round-off), then one step of the same field makes the landmarks
//    land on their targets to round-off (it moves them by the RK4 truncation error).
// 5. Repair: faces the flow flipped (slivers sheared past their width) are unflipped by moving
//    their corners part of the way to their neighbours' mean on the sphere, the part that keeps
//    their faces' areas nearest the input's.
// 6. Restoration: the flow keeps areas, the mesh's chord triangles only to first order in their
//    size (their edges are the flow's secants); the surface map's polish brings the face areas
//    back to the input's, the faces that carry a landmark held still (they keep the flow's
//    exact motion).
//
// Dense registration (a template and a per-vertex scalar of both surfaces, for example FreeSurfer's
// curvature or sulcal depth): between steps 4 and 5, Gauss-Newton iterations that pull the
// subject's scalar onto the template's, coarse to fine (SphereMatchOptions::widths), each by a
// field of the same kind:
//  a. both scalars smoothed at the level's scale (neighbour averaging on each mesh, a diffusion
//     of about smoothing x width) and standardised (area-weighted mean 0, spread 1);
//  b. every subject vertex x_i located on the template's sphere (vpm::SphereLocator): the
//     template's value g(x_i) and its gradient tangent to the sphere (per-vertex gradients,
//     interpolated), the residual e_i = g(x_i) - f_i;
//  c. the field v(x) = x × sum_j H(x, c_j) u_j with its centres c_j on an icosphere of about the
//     level's width: the weights minimise sum_i a_i (e_i + grad g(x_i) . v(x_i))^2 + mu u^T K u
//     (a_i the vertex's share of the area, K the centres' Gram matrix: the field's smoothness,
//     mu = ridge x the data term's mean diagonal over the Gram's), one dense Cholesky solve;
//  d. every vertex (and every landmark) moved through the field (RK4), the step scaled so that no
//     vertex moves more than max_move x width and halved until the mismatch (the area-weighted
//     mean of e^2) decreases and no face flips (flipped slivers repaired, each corner moved the
//     whole way to its neighbours' mean, when that changes the face areas by at most 0.1 %); a level ends when a step gains less than 0.1 %
//     of the mismatch, or after `iterations`.
// With landmarks, the system of step c also pulls the field's value at each landmark to zero
// (weighted 100 times the data term), only the levels narrower than the landmarks' mean
// nearest-neighbour chord run (the landmark flow set the coarser scales), and after the levels
// one more landmark flow puts the landmarks back onto their targets exactly. Steps 5-6 follow.
#include <Eigen/Core>
#include <vector>

#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/surface_map.hpp"

namespace vpm {

/// The dense iterations of a registration with a template (see the top of this header).
struct SphereMatchOptions {
  /// Gauss-Newton iterations at most per level (0: none, landmarks only).
  int iterations = 8;
  /// Gaussian widths of the levels (chord length), coarse first; each level's centres are the
  /// vertices of the icosphere whose edges are at most the width (42, 162, 642, 2,562 for these;
  /// the finest level chosen on the development set, docs/surfaces.md "Measured"). A level
  /// narrower than 1.5 times the subject's mean edge is left out (a 5k-face surface stops at
  /// 0.14), and with landmarks one wider than their mean spacing.
  std::vector<double> widths = {0.56, 0.28, 0.14, 0.07};
  double smoothing = 0.5;  ///< the scalars' smoothing scale, x the level's width
  double ridge = 0.05;     ///< the smoothness weight mu, relative to the data term
  double max_move = 0.25;  ///< the largest vertex move of one iteration, x the level's width
  /// Without landmarks: first, when the two scalars smoothed at the coarsest width correlate
  /// below 0.75 as the maps are, the rotation that best correlates them (a grid of rotations
  /// refined by a pattern search), applied when it at least halves 1 - that correlation (two
  /// sphere maps are unique only up to a rotation; the dense steps do not undo one from far). A
  /// subject onto itself keeps the identity.
  bool rotation_search = true;
};

/// The template of a dense registration: a surface mapped to the sphere and its per-vertex
/// scalar (the subject's counterpart is registered onto it).
struct SphereTemplate {
  Points sphere;           ///< m x 3 on the unit sphere
  Triangles faces;         ///< outward-oriented, fold-free on the sphere
  Eigen::VectorXd values;  ///< length m
};

/// The template of a dense registration in the disk: a surface mapped to the disk and its
/// per-vertex scalar.
struct DiskTemplate {
  Points disk;             ///< m x 3 in the unit disk (z = 0), its boundary loop on the circle
  Triangles faces;         ///< counter-clockwise, fold-free in the disk
  Eigen::VectorXd values;  ///< length m
};

/// One level of the dense iterations.
struct SphereMatchLevel {
  double width = 0;
  int centres = 0, iterations = 0;
  /// Disk levels: times the face areas were brought back towards the input's because every
  /// halving of a step crushed faces (always 0 on the sphere).
  int reliefs = 0;
  double mismatch_before = 0, mismatch_after = 0;  ///< area-weighted mean squared residual of the level's standardised scalars
};

/// What the dense iterations did (empty levels: none ran).
struct SphereMatchReport {
  std::vector<SphereMatchLevel> levels;
  /// Area-weighted correlation of the subject's scalar with the template's at the subject's
  /// vertices (both unsmoothed), before and after the dense iterations.
  double correlation_before = 0, correlation_after = 0;
  /// The rotation search (without landmarks): whether it ran, the smoothed scalars' correlation
  /// without a rotation and at the best one found, the rotation applied (identity when it did not
  /// halve 1 - correlation).
  bool rotation_searched = false;
  double search_correlation_identity = 0, search_correlation_best = 0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  double seconds = 0;
};

struct SurfaceRegistrationOptions {
  int steps = 32;  ///< K: RK4 steps over t in [0, 1]
  /// Gaussian width = width_factor x the mean angular spacing of each landmark to its nearest
  /// (the smaller of the landmark and target sets' means). 0: chosen among 0.5, 1, 1.5, 2, 3, 4
  /// by leave-one-out (the factor whose field best predicts each landmark's first step from the
  /// others'): wide for a smooth deformation, narrow for landmarks that move independently;
  /// when the repair leaves a face flipped, the flow is run again with the next narrower factor.
  double width_factor = 0;
  bool rigid = true;  ///< the rigid step first
  /// The restoration: at most this many Gauss-Newton steps of the surface map's polish on the
  /// face areas against the input's (0: none), the vertices of the faces that carry a landmark
  /// held still, until the face area mean |r - 1| is at most restore_tolerance.
  int restore_rounds = 30;
  double restore_tolerance = 0.001;
  SphereMatchOptions match{};  ///< the dense iterations (with a template)
};

struct SurfaceRegistrationResult {
  Points points;                                       ///< n x 3 on the unit sphere, same rows
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();  ///< the rigid step
  double width = 0;                                    ///< the Gaussian's (chord length)
  double width_factor = 0;                             ///< the factor used (given or chosen)
  double landmark_rms_error = 0, landmark_max_error = 0;  ///< |landmark's image - target|, after the last step
  double flow_landmark_max_error = 0;                  ///< before it: the RK4 steps' error
  SurfaceMetrics flow_metrics;                         ///< after the flow, before the restoration
  int restore_rounds = 0, held_vertices = 0;           ///< the restoration's steps, vertices held still
  int repaired_faces = 0;                              ///< faces the flow flipped, repaired before it
  SurfaceMetrics metrics;                              ///< of `points` against the input
  SphereMatchReport match;                             ///< the dense iterations (with a template)
  double seconds = 0;
};

/// Registers the sphere-mapped surface `sphere` (n x 3, |x| = 1 within 1e-4; normalised) with
/// faces `faces` by moving `landmarks` (L x 3 on the sphere) onto `targets`. Throws InputError for
/// points off the sphere, fewer than one landmark, counts that differ, or a landmark and its
/// target antipodal (no unique great circle); NumericalError when the field cannot be fitted.
/// `device` (may be null: the host) is where the flows' advections run (kernels/register.cl's
/// rk4_advect_soa; the host device: the same code on the host threads); the rest runs on the host.
SurfaceRegistrationResult register_on_sphere(const Points& sphere, const Triangles& faces, const Points& landmarks,
                                             const Points& targets, const SurfaceRegistrationOptions& options = {},
                                             Device* device = nullptr);

/// Registers a surface mapped to the unit disk (vpm::map_to_disk's points: z = 0, the boundary
/// loop on the circle) by moving `landmarks` onto `targets` (L x 3, z = 0, both strictly inside
/// the disk, |x| <= 0.999): the steps above in the plane. The rigid step is the rotation about the
/// centre; the pathlines are straight; the field is v = J grad psi (J the quarter turn) with the
/// stream function psi(x) = (1 - |x|^2) sum_j b_j . grad_y [(1 - |y|^2) exp(-lambda |x - y|^2)]
/// at y = y_j, zero on the circle: divergence-free and tangent to the circle, so boundary vertices
/// slide along it and interior ones stay inside (the boundary loop is put back on the circle
/// against round-off). InputError for points outside the disk or landmarks on its edge. `device`
/// as on the sphere (the flows' advections: kernels/rbf_advect.clh's disk field).
SurfaceRegistrationResult register_in_disk(const Points& disk, const Triangles& faces, const Points& landmarks,
                                           const Points& targets, const SurfaceRegistrationOptions& options = {},
                                           Device* device = nullptr);

/// Dense registration in the disk: the subject's disk map `disk` (n x 3) and its per-vertex
/// scalar `values` registered onto `templ`'s by the steps a-d above in the plane, each step's
/// field the disk's stream-function field (boundary vertices slide along the circle): the
/// scalars smoothed on a square grid of nodes (spacing half the smoothing scale) instead of an
/// icosphere's, the field's centres on a triangular lattice of spacing 0.94 x the level's width
/// instead of an icosphere's vertices, the rotation search (without landmarks) over rotations
/// about the centre. The landmarks (L >= 0) are moved exactly onto their targets as in the landmark
/// registration. InputError as the sphere's dense registration's, for points outside the disk.
/// `device` as above (the dense steps' advections too).
SurfaceRegistrationResult register_in_disk(const Points& disk, const Triangles& faces, const Eigen::VectorXd& values,
                                           const DiskTemplate& templ, const Points& landmarks, const Points& targets,
                                           const SurfaceRegistrationOptions& options = {}, Device* device = nullptr);

/// Dense registration: the subject's sphere map `sphere` (n x 3) with faces `faces` and its
/// per-vertex scalar `values` (length n) registered onto `templ`'s, the landmarks (L x 3, L >= 0:
/// none) moved exactly onto their targets as above. InputError for counts that differ, points
/// off the sphere, scalars that are not finite or constant. `device` as above (the dense steps'
/// advections too).
SurfaceRegistrationResult register_on_sphere(const Points& sphere, const Triangles& faces, const Eigen::VectorXd& values,
                                             const SphereTemplate& templ, const Points& landmarks, const Points& targets,
                                             const SurfaceRegistrationOptions& options = {}, Device* device = nullptr);

/// {"steps", "width", "width_factor", "rotation_angle_deg", "landmark_rms_error", "landmark_max_error",
///  "flow_landmark_max_error", "flow": to_json(SurfaceMetrics) (before the restoration),
///  "restore": {"rounds", "held_vertices", "repaired_faces"}, "final": to_json(SurfaceMetrics),
///  "match": {"correlation_before", "correlation_after", "rotation_search": {"correlation_identity",
///  "correlation_best", "angle_deg"} (when it ran), "levels": [{"width", "centres",
///  "iterations", "mismatch_before", "mismatch_after"}], "seconds"} (dense registrations only),
///  "timings_s": {"total"}}
Json to_json(const SurfaceRegistrationResult& result, const SurfaceRegistrationOptions& options);

}  // namespace vpm
