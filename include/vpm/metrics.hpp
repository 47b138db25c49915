#pragma once
// Distortion metrics of docs/design.md 5, with the names the report JSON uses.
#include <Eigen/Core>

#include "vpm/json.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

class Device;

/// Statistics of a ratio field r (after / before, both meshes normalised to total volume 1).
struct RatioStats {
  double mean_abs_dev = 0;  ///< mean |r - 1| (the paper's "volume distortion")
  double std_log = 0;       ///< standard deviation of log r
  double p99_abs_log = 0;   ///< 99th percentile of |log r|
  double max_abs_log = 0;   ///< max |log r|
  double min = 0, max = 0;  ///< extreme ratios
};
/// Statistics of `ratios`. Ratios <= 0 (inverted elements) enter the logs as 1e-300.
RatioStats ratio_stats(const Eigen::VectorXd& ratios);

/// Metrics of a map of `reference` (the input mesh) to `mapped` (same tets, moved vertices).
struct MapMetrics {
  int inverted_tets = 0;              ///< mapped tets with signed volume <= 0
  RatioStats vertex_volume_ratio;     ///< dual volume ratios (normalised)
  RatioStats tet_volume_ratio;        ///< tet volume ratios (normalised)
  double boundary_max_radius_error = 0;  ///< max | |x| - 1 | over boundary vertices of `mapped`
  Eigen::VectorXd vertex_ratio;       ///< per-vertex ratios r_i (length n)
  Eigen::VectorXd tet_ratio;          ///< per-tet ratios r_t (length m)
};

/// Normalised volume ratios of `mapped_volumes` against `reference_volumes` (signed tet
/// volumes, length m, of the same `tets` on n vertices): tet_ratio (m) = (v1_t / sum v1) /
/// (v0_t / sum v0), vertex_ratio (n) the same for dual volumes (a quarter of each incident
/// tet's volume; NaN at a vertex in no tet).
void volume_ratios(const Eigen::VectorXd& reference_volumes, const Eigen::VectorXd& mapped_volumes,
                   const Tets& tets, Eigen::Index n, Eigen::VectorXd& tet_ratio, Eigen::VectorXd& vertex_ratio);

/// The two summary numbers the map's iterations watch, computed on the host: mean |r - 1| of the
/// vertex (dual) and tet volume ratios of `mapped` against `reference` (both n x 3, same
/// `tets`; vertices in no tet are skipped), and the tets with signed volume <= 0.
struct DistortionPair {
  double vertex = 0, tet = 0;
  int folds = 0;
};
DistortionPair volume_distortion(const Points& reference, const Points& mapped, const Tets& tets);

/// Computes MapMetrics. `reference_vertices` and `mapped_vertices` are n x 3 with the same
/// `tets` (m x 4). Volumes come from `device` (host or OpenCL). `boundary_mask` (n; nonzero on
/// the boundary vertices, as boundary_vertex_mask gives), when the caller has it, saves finding
/// the boundary again; it must be the mask of `tets`.
MapMetrics map_metrics(Device& device, const Points& reference_vertices, const Points& mapped_vertices,
                       const Tets& tets, const std::vector<char>* boundary_mask = nullptr);

/// The report object {"inverted_tets", "vertex_volume_ratio": {...}, "tet_volume_ratio": {...},
/// "boundary_max_radius_error"}.
Json to_json(const MapMetrics& metrics);
Json to_json(const RatioStats& stats);

}  // namespace vpm
