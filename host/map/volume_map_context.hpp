#pragma once
// Private: the state one volume-preserving map carries through its rounds (vpm/volume_map.hpp)
// and the steps the rounds are made of (map/volume_map_steps.cpp). The driver is
// map/volume_map.cpp, the round loops map/volume_map_rounds.cpp.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "map/moser_field.hpp"
#include "mesh/mesh_volumes.hpp"
#include "map/polish.hpp"
#include "map/volume_map_solve.hpp"
#include "vpm/mesh.hpp"
#include "vpm/polish.hpp"
#include "vpm/volume_map.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// What polish_volumes adds to the rounds' machinery: only the polish rounds run, with pins,
/// anchors and holds (vpm/polish.hpp). volume_preserving_map runs with none.
struct PolishConstraints {
  bool only = false;
  std::vector<char> pinned;
  std::vector<VolumeAnchor> anchors;
  std::vector<VolumeHold> holds;
  const TetTopology* topology = nullptr;  ///< of the tets, when the caller built it (else set_up does)
};

/// Which rounds a map runs: vpm's (Moser rounds, then the polish) or a peer's
/// (vpm/volume_map_peers.hpp).
enum class Rounds { moser, paper, vsem };
const char* to_string(Rounds r);

struct MapContext {
  Device& dev;
  const Points& ref;
  const Tets& tets;
  const VolumeMapOptions& opt;
  const PolishConstraints& pc;
  Rounds rounds = Rounds::moser;
  int paper_steps = 50;  ///< the paper's loop: its explicit steps (VolumeMapPeerOptions::paper_steps)
  int n = 0, m = 0;
  bool slide = true;
  std::vector<char> boundary;
  std::vector<char> frozen;       // never moved by untangling: boundary or pinned
  std::vector<int> nbr;
  std::vector<int> vertex_tet;    // one tet incident to each vertex
  Eigen::VectorXd ref_dual;       // input dual volumes / input total volume
  Eigen::VectorXd ref_tet;        // input tet volumes / input total volume
  std::unique_ptr<MapSolver> solver;
  std::unique_ptr<Advector> advector;      // the Moser rounds' advection where placed (method moser)
  std::unique_ptr<MeshVolumes> volumes;  // fold checks and dual volumes, on the context's device
  MoserField field;  // a Moser round's field, its arrays reused by the next round (freed after the rounds)
  Eigen::VectorXd psi;
  Triangles bfaces;  // boundary faces (outward), from the same face sort as nbr
  std::vector<char> freedom;                          // polish: free / tangent / fixed per vertex
  std::unique_ptr<Polisher> polisher;         // the polish where placed, built on first use
  Placement placement;                                // where the parts below run, and why
  bool polish_on_device = false;                      // VolumeMapOptions::polish resolved
  bool gradients_on_device = false;                   // the advector computes the field's gradients

  MapContext(Device& d, const Points& r, const Tets& t, const VolumeMapOptions& o, const PolishConstraints& p)
      : dev(d), ref(r), tets(t), opt(o), pc(p) {}
  bool pinned(int v) const { return !pc.pinned.empty() && pc.pinned[static_cast<size_t>(v)]; }
  /// The advector as the device's, for the field made from psi there (gradients_on_device is
  /// placed only with the device's advection; std::logic_error otherwise).
  DeviceAdvector& device_advector() const;
};

/// volume_preserving_map with the polish constraints `pc` (polish_volumes: pc.only) and the
/// rounds `rounds` (a peer's: volume_map_peer, with `paper_steps`).
VolumeMapResult map_volumes(Device& device, const Points& reference, const Tets& tets, Points& ball,
                            const VolumeMapOptions& options, const PolishConstraints& pc,
                            Rounds rounds = Rounds::moser, int paper_steps = 50);

/// Tets of `x` with signed volume <= 0 (volumes on the context's device).
int count_folds(MapContext& c, const Points& x);

/// Local untangling of the folded tets of x (boundary fixed; when sliding and `before` is given,
/// boundary triangles flipped on the sphere are unflipped first). Adds its time to *seconds.
/// Returns the folds left.
int untangle_folds(MapContext& c, Points& x, double* seconds, const Points* before = nullptr);

/// One Moser round on [0, t_end] (docs/design.md 4.1 step 5): x in/out; statistics into `r`.
void moser_round(MapContext& c, Points& x, double t_end, VolumeMapRound& r);

/// The paper's explicit step (4.3): re-solve on the current geometry, x += dt grad psi / rho.
void paper_step(MapContext& c, Points& x, double dt, VolumeMapRound& r);

/// One Gauss-Newton direction of the polish on the relative tet volumes (map/polish.hpp), on
/// the device or the host threads (VolumeMapOptions::polish). x is not changed.
void polish_step(MapContext& c, const Points& x, VolumeMapRound& r, Points& dx_out, int iterations);

/// Moves the boundary vertices that are not pinned back onto the unit sphere (when sliding).
void project_boundary(const MapContext& c, Points& x);

/// The Moser / paper / vsem rounds of volume_preserving_map: x in/out, rounds appended to
/// `res`, `d` in: the distortion of x, out: after the last accepted round.
void run_rounds(MapContext& c, Points& x, VolumeMapResult& res, DistortionPair& d);

/// The polish rounds after them (vpm's rounds only).
void run_polish(MapContext& c, Points& x, VolumeMapResult& res, DistortionPair& d);

}  // namespace vpm::detail
