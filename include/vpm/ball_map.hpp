#pragma once
// The whole `vpm map` stage as one call: a validated tet mesh -> fold-free initial map to the
// unit ball (vpm/initial_map.hpp) -> volume-preserving map (vpm/volume_map.hpp) -> metrics ->
// the output mesh with its fields and the report of DESIGN.md section 6.
#include <string>

#include "vpm/initial_map.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/metrics.hpp"
#include "vpm/validate.hpp"
#include "vpm/volume_map.hpp"

namespace vpm {

class Device;

struct BallMapOptions {
  InitialMapOptions initial{};
  /// volume.rounds == 0 stops after the initial map.
  VolumeMapOptions volume{};
};

struct BallMap {
  /// The mapped mesh: input vertices first (input order), then the vertices inserted by the
  /// boundary-edge split; positions in the closed unit ball (boundary on the sphere), every tet
  /// positively oriented. Input point and cell fields carried; point fields
  /// `original_position` (n x 3, input coordinates) and `vertex_volume_ratio`, cell field
  /// `tet_volume_ratio` (normalised ratios against the input, DESIGN.md 5).
  TetMesh mesh;
  MapMetrics initial;  ///< metrics of the initial map
  MapMetrics final;    ///< metrics of the returned map (inverted_tets == 0)
  /// {"device", "input": {"vertices","tets","min_dihedral_deg","reoriented_tets"},
  ///  "refined": {"vertices","tets"}, "initial": METRICS, "final": METRICS, "rounds": [...],
  ///  "timings_s": {"total","initial_map","volume_map","volume_map_solve","volume_map_field",
  ///  "volume_map_advect","volume_map_untangle","metrics"}, "initial_map": {...},
  ///  "volume_map": {...} (when rounds != 0)}. The caller adds "read"/"write" timings.
  Json report;
};

/// Maps `input` (validated by validate_mesh, whose report is `validation`) to the unit ball so
/// that local volumes are preserved. `source` names the input in messages. Runs on `device`.
/// Throws InputError for a mesh that is not a ball topologically and NumericalError (message
/// naming `source`, what was reached and the input's smallest dihedral angle) when no fold-free
/// map could be made: a folded map is never returned.
BallMap map_to_ball(Device& device, const TetMesh& input, const ValidationReport& validation,
                    const std::string& source, const BallMapOptions& options = {});

}  // namespace vpm
