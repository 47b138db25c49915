// polish_volumes (vpm/polish.hpp): the volume map's polish rounds on their own, with pins,
// anchors and holds checked here and carried through the rounds' machinery as
// PolishConstraints (map/volume_map_context.hpp).
#include "vpm/polish.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "map/volume_map_context.hpp"
#include "vpm/error.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {

// Anchor vertices: in range, interior, not pinned; weights not all zero.
void check_anchors(const Points& reference, const std::vector<char>& boundary, const PolishOptions& opt) {
  if (opt.anchors.empty()) return;
  for (size_t a = 0; a < opt.anchors.size(); ++a) {
    const VolumeAnchor& an = opt.anchors[a];
    double w2 = 0;
    for (int k = 0; k < 4; ++k) {
      const int v = an.vertices[static_cast<size_t>(k)];
      const std::string where = "polish: anchor " + std::to_string(a) + " vertex " + std::to_string(v);
      if (v < 0 || v >= reference.rows()) throw InputError(where + " is out of range");
      if (boundary[static_cast<size_t>(v)]) throw InputError(where + " is on the boundary");
      if (!opt.pinned.empty() && opt.pinned[static_cast<size_t>(v)]) throw InputError(where + " is pinned");
      w2 += an.weights[static_cast<size_t>(k)] * an.weights[static_cast<size_t>(k)];
    }
    if (!(w2 > 0)) throw InputError("polish: anchor " + std::to_string(a) + " has no weight");
  }
}

void check_constraints(const Points& reference, const TetTopology& topology, const PolishOptions& opt) {
  if (!opt.pinned.empty() && opt.pinned.size() != static_cast<size_t>(reference.rows()))
    throw InputError("polish: pinned has " + std::to_string(opt.pinned.size()) + " entries for " +
                     std::to_string(reference.rows()) + " vertices");
  for (const VolumeHold& h : opt.holds)
    for (int v : h.vertices)
      if (v < 0 || v >= reference.rows()) throw InputError("polish: a hold's vertex is out of range");
  if (opt.rounds < 0) throw InputError("polish: rounds must be >= 0");
  if (opt.iterations < 1) throw InputError("polish: iterations must be >= 1");
  check_anchors(reference, topology.boundary_vertex, opt);
}

}  // namespace

int polish_iterations_for(int base, long long tets) {
  return static_cast<int>(std::lround(base * std::max(1.0, std::cbrt(static_cast<double>(tets) / 30000.0))));
}

VolumeMapResult polish_volumes(Device& device, const Points& reference, const Tets& tets, Points& x,
                               const PolishOptions& options) {
  if (tets.rows() > 0 && (tets.minCoeff() < 0 || tets.maxCoeff() >= reference.rows()))
    throw InputError("polish: tet vertex index out of range");
  TetTopology built;
  if (options.topology && (options.topology->neighbours.size() != 4 * static_cast<size_t>(tets.rows()) ||
                           options.topology->boundary_vertex.size() != static_cast<size_t>(reference.rows())))
    throw InputError("polish: the topology given is not of these tets");
  const TetTopology& topology =
      options.topology ? *options.topology : (built = tet_topology(static_cast<int>(reference.rows()), tets));
  check_constraints(reference, topology, options);
  VolumeMapOptions vo;
  vo.boundary = options.boundary == MapBoundary::automatic ? MapBoundary::slide : options.boundary;
  vo.polish_rounds = options.rounds;
  vo.polish_min_gain = options.min_gain;
  vo.polish_iterations = polish_iterations_for(options.iterations, tets.rows());
  vo.polish = options.place;
  vo.local_untangle = options.local_untangle;
  vo.deadline = options.deadline;
  vo.progress = options.progress;
  detail::PolishConstraints pc;
  pc.only = true;
  pc.pinned = options.pinned;
  pc.anchors = options.anchors;
  pc.holds = options.holds;
  pc.topology = &topology;
  return detail::map_volumes(device, reference, tets, x, vo, pc);
}

}  // namespace vpm
