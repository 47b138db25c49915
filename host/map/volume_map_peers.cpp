// The volume map's peers (vpm/volume_map_peers.hpp): vpm's round machinery with their rounds.
#include "vpm/volume_map_peers.hpp"

#include "map/volume_map_context.hpp"
#include "vpm/error.hpp"

namespace vpm {

VolumeMapPeer parse_volume_map_peer(const std::string& s) {
  if (s == "paper") return VolumeMapPeer::paper;
  if (s == "vsem") return VolumeMapPeer::vsem;
  throw InputError("volume map peer '" + s + "' is not one of paper, vsem");
}

const char* to_string(VolumeMapPeer p) { return p == VolumeMapPeer::paper ? "paper" : "vsem"; }

VolumeMapResult volume_map_peer(Device& dev, const Points& reference, const Tets& tets, Points& ball,
                                const VolumeMapOptions& opt, const VolumeMapPeerOptions& peer) {
  static const detail::PolishConstraints none;
  const detail::Rounds rounds = peer.peer == VolumeMapPeer::paper ? detail::Rounds::paper : detail::Rounds::vsem;
  return detail::map_volumes(dev, reference, tets, ball, opt, none, rounds, peer.paper_steps);
}

}  // namespace vpm
