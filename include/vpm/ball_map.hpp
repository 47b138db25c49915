#pragma once
// The whole `vpm map` stage as one call: a validated tet mesh -> fold-free initial map to the
// unit ball (vpm/initial_map.hpp) -> volume-preserving map (vpm/volume_map.hpp) -> metrics ->
// the output mesh with its fields and the report of docs/design.md 6.
#include <optional>
#include <string>

#include "vpm/initial_map.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh.hpp"
#include "vpm/metrics.hpp"
#include "vpm/validate.hpp"
#include "vpm/volume_map.hpp"
#include "vpm/volume_map_peers.hpp"

namespace vpm {

class Device;

struct BallMapOptions {
  InitialMapOptions initial{};
  /// volume.rounds == 0 stops after the initial map.
  VolumeMapOptions volume{};
  /// A peer's rounds instead of vpm's (vpm/volume_map_peers.hpp; `vpm map --method`, for comparison).
  std::optional<VolumeMapPeerOptions> peer;
  /// Time budget of the whole map, handed to both stages (their own deadlines when not set).
  /// When it stops the rounds, the map reached so far is returned with convergence.converged
  /// false and reason "time_budget"; when it passes before the initial map is fold-free,
  /// NumericalError. volume.progress also receives the initial map's lines when
  /// initial.progress is empty.
  Deadline deadline{};
};

/// Seconds spent in the stages of map_to_ball.
struct BallMapTimings {
  double initial_map = 0, volume_map = 0, metrics = 0, total = 0;
};

/// Whether the map reached its tolerance. Checked only when the rounds ran "until tolerance"
/// (VolumeMapOptions::rounds == -1); a fixed number of rounds is what the caller asked for.
struct MapConvergence {
  bool checked = false;
  bool converged = true;   ///< final vertex mean |r-1| <= tolerance (true when not checked)
  double tolerance = 0;
  double reached = 0;      ///< final vertex mean |r-1|
  std::string reason;      ///< why the rounds stopped (VolumeMapResult::stop_reason; "time_budget": checked)
};

/// {"checked", "converged", "tolerance", "reached", "reason"}
Json to_json(const MapConvergence& convergence);

struct BallMap {
  /// The mapped mesh: input vertices first (input order), then the vertices inserted by the
  /// boundary-edge split; positions in the closed unit ball (boundary on the sphere), every tet
  /// positively oriented. Input point and cell fields carried; point fields
  /// `original_position` (n x 3, input coordinates) and `vertex_volume_ratio`, cell field
  /// `tet_volume_ratio` (normalised ratios against the input, docs/design.md 5).
  TetMesh mesh;
  MapMetrics initial;  ///< metrics of the initial map
  MapMetrics final;    ///< metrics of the returned map (inverted_tets == 0)
  std::string device;  ///< Device::name() of the device that ran it
  int input_vertices = 0, input_tets = 0;
  double input_min_dihedral_deg = 0;  ///< from the validation report
  int input_reoriented_tets = 0;      ///< from the validation report
  int input_sliver_tets = 0;          ///< from the validation report
  int refined_vertices = 0, refined_tets = 0;  ///< after the boundary-edge split
  InitialMapReport initial_map;        ///< what the initial map did
  std::optional<VolumeMapResult> volume_map;  ///< absent when options.volume.rounds == 0
  MapConvergence convergence;
  /// Where each part of the map ran and why (the equal-area steps, the advection, the field's
  /// gradients, the polish; vpm/placement.hpp): JSON "placement".
  Placement placement;
  BallMapTimings timings;
};

/// The report of docs/design.md 6: {"device", "input": {"vertices","tets","min_dihedral_deg",
/// "reoriented_tets","sliver_tets"}, "refined": {"vertices","tets"}, "initial": METRICS, "final": METRICS,
/// "rounds": [...], "timings_s": {"total","initial_map","volume_map","volume_map_solve",
/// "volume_map_field","volume_map_advect","volume_map_untangle","metrics"}, "initial_map": {...},
/// "volume_map": {...} (when it ran), "converged": bool (when checked), "convergence": {...}}.
/// `vpm map` adds "read"/"write" to "timings_s".
Json to_json(const BallMap& map);

/// The whole-process peak memory (bytes) of reading, validating and mapping a mesh of `tets`
/// tets with `vpm map`: a line fitted to measured peaks (docs/robustness.md, "Limits"), the
/// largest of the host and the PoCL device at every size measured.
double map_memory_estimate(long long tets);

/// Refuses (InputError naming `source`, exit status 2) a map whose map_memory_estimate() does
/// not fit in memory_budget() (vpm/memory.hpp; VPM_MAX_MEMORY overrides), before any work.
void require_map_memory(long long tets, const std::string& source);

/// Maps `input` (validated by validate_mesh, whose report is `validation`) to the unit ball so
/// that local volumes are preserved. `source` names the input in messages. Runs on `device`.
/// Calls require_map_memory() first.
/// Throws InputError for a mesh that is not a ball topologically and NumericalError (message
/// naming `source`, what was reached and the input's smallest dihedral angle) when no fold-free
/// map could be made: a folded map is never returned.
BallMap map_to_ball(Device& device, const TetMesh& input, const ValidationReport& validation,
                    const std::string& source, const BallMapOptions& options = {});

}  // namespace vpm
