#pragma once
// Distortion metrics of DESIGN.md section 5, with the names the report JSON uses.
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

/// Computes MapMetrics. `reference_vertices` and `mapped_vertices` are n x 3 with the same
/// `tets` (m x 4). Volumes come from `device` (host or OpenCL).
MapMetrics map_metrics(Device& device, const Points& reference_vertices,
                       const Points& mapped_vertices, const Tets& tets);

/// The report object {"inverted_tets", "vertex_volume_ratio": {...}, "tet_volume_ratio": {...},
/// "boundary_max_radius_error"}.
Json to_json(const MapMetrics& metrics);
Json to_json(const RatioStats& stats);

}  // namespace vpm
