#pragma once
// The peers of the volume-preserving map (vpm/volume_map.hpp), kept to compare vpm's map with:
// the benchmarks run them (bench/volume_map.cpp; docs/volume_map.md "Peers"), the product does
// not. Both run through the same fold-safe rounds as vpm's map (every round fold-checked,
// untangled locally, shortened or discarded) and return the same report.
//  * paper: the paper's discrete loop (4.3): at each of `paper_steps` steps recompute
//    rho = m / V from the current geometry, re-solve, step x += dt grad psi / rho (dt = 1/K).
//    A step that folds is retried with dt halved. It stalls (docs/design.md 4.2).
//  * vsem: each tet's stiffness (on the input geometry) multiplied by its accumulated volume
//    ratio, boundary frozen, harmonic (Dirichlet) re-solve per iteration (Yueh et al. 2019 style
//    fixed point).
#include <string>

#include "vpm/volume_map.hpp"

namespace vpm {

enum class VolumeMapPeer { paper, vsem };
/// "paper", "vsem"; InputError otherwise (message: "volume map peer 'NAME' is not one of paper, vsem").
VolumeMapPeer parse_volume_map_peer(const std::string& name);
const char* to_string(VolumeMapPeer p);

struct VolumeMapPeerOptions {
  VolumeMapPeer peer = VolumeMapPeer::paper;
  /// Explicit steps K of the paper's loop (dt = 1/K); its rounds when `rounds` is -1.
  int paper_steps = 50;
};

/// volume_preserving_map with a peer's rounds instead of the Moser rounds and the polish:
/// `options` as there (rounds, max_rounds, tolerance, boundary: automatic is fixed, the solver),
/// VolumeMapResult::method names the peer.
VolumeMapResult volume_map_peer(Device& device, const Points& input_vertices, const Tets& tets, Points& ball,
                                const VolumeMapOptions& options, const VolumeMapPeerOptions& peer);

}  // namespace vpm
