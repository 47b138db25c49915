#pragma once
// Private: the search direction of one polish step of the volume map (vpm/volume_map.hpp):
// CGLS from dx = 0 on the linearised relative tet volumes,
//   min |A dx - b|,  A_(t, v) = vol_t grad phi_v / target_t,  b_t = 1 - vol_t / target_t,
// early-stopped after `iterations` (the minimum-norm start is the regularisation), with each
// vertex free, tangent to the unit sphere, or fixed, and each anchor's weighted sum of its four
// vertices' dx zero (VolumeAnchor; the orthogonal projection onto those planes). The iteration is
// written once (map/polish_cgls.hpp); the host threads and the OpenCL kernels (kernels/polish.cl)
// are its two backends.
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/polish.hpp"

namespace vpm {
class Device;
}

namespace vpm::detail {

/// Freedom of each vertex in a polish step (kernels/polish.cl's flags). kPolishAnchored: a free
/// vertex of an anchor group, projected with its group (set by DevicePolisher from the anchors;
/// polish_freedom never returns it).
enum PolishFreedom : char { kPolishFree = 0, kPolishTangent = 1, kPolishFixed = 2, kPolishAnchored = 3 };

/// Per-vertex freedom: pinned -> fixed; boundary -> tangent when sliding, else fixed.
/// `boundary` n entries, `pinned` n entries or empty.
std::vector<char> polish_freedom(const std::vector<char>& boundary, bool slide, const std::vector<char>& pinned);

/// The anchors' constraints grouped: anchors that share a vertex form one group, projected
/// jointly. Per group g: its vertices vertices[ptr[g] .. ptr[g+1]) (sorted, each in one group),
/// and the k x k projector P = I - W^T (W W^T)^+ W (row-major at matrix[offset[g]]), W the
/// group's anchors x vertices weight matrix; dx_V <- P dx_V per coordinate.
struct AnchorGroups {
  std::vector<int> ptr{0}, vertices, offset;
  std::vector<double> matrix;
  int groups() const { return static_cast<int>(ptr.size()) - 1; }
};
AnchorGroups anchor_groups(const std::vector<VolumeAnchor>& anchors);

struct PolishDirection {
  Points dx;           ///< n x 3
  int iterations = 0;  ///< CGLS iterations done (fewer than asked when A^T r vanished)
  double residual = 0; ///< |b - A dx| / |b|
};

/// Host reference. `x` n x 3 positions, `tets` m x 4, `target` m target volumes (same total as
/// x's), `freedom` n entries (polish_freedom), `anchors` on free vertices; `holds` (VolumeHold)
/// add their rows (right-hand side 0) to the least squares.
PolishDirection polish_direction_host(const Points& x, const Tets& tets, const Eigen::VectorXd& target,
                                      const std::vector<char>& freedom, const std::vector<VolumeAnchor>& anchors,
                                      int iterations, const std::vector<VolumeHold>& holds = {});

/// The polish's direction on one backend, chosen once per map (Placement's "polish"): callers
/// ask `direction` and do not know which. make_polisher builds one.
class Polisher {
 public:
  virtual ~Polisher() = default;
  /// The direction from positions `x` (n x 3) towards the tets' `target` volumes (m, the same
  /// total as x's) after at most `iterations` CGLS iterations.
  virtual PolishDirection direction(const Points& x, const Eigen::VectorXd& target, int iterations) = 0;
};

/// polish_direction_host on the host threads, with the tets, freedom, anchors and holds given
/// here (held by reference: they must outlive the polisher).
class HostPolisher final : public Polisher {
 public:
  HostPolisher(const Tets& tets, const std::vector<char>& freedom, const std::vector<VolumeAnchor>& anchors,
               const std::vector<VolumeHold>& holds)
      : tets_(tets), freedom_(freedom), anchors_(anchors), holds_(holds) {}
  PolishDirection direction(const Points& x, const Eigen::VectorXd& target, int iterations) override {
    return polish_direction_host(x, tets_, target, freedom_, anchors_, iterations, holds_);
  }

 private:
  const Tets& tets_;
  const std::vector<char>& freedom_;
  const std::vector<VolumeAnchor>& anchors_;
  const std::vector<VolumeHold>& holds_;
};

/// OpenCL: connectivity (vertex -> row-corner incidence), freedom and the holds' rows uploaded
/// once; each call uploads x and target, runs the iterations without a host synchronisation,
/// reads dx back. The holds' rows sit after the tets' in the kernels' A (same shape: four
/// vertices with a 3-vector each), so the same kernels apply both.
class DevicePolisher final : public Polisher {
 public:
  DevicePolisher(Device& device, const Tets& tets, int num_vertices, const std::vector<char>& freedom,
                 const std::vector<VolumeAnchor>& anchors, const std::vector<VolumeHold>& holds = {});
  ~DevicePolisher() override;
  PolishDirection direction(const Points& x, const Eigen::VectorXd& target, int iterations) override;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The polisher of `device` when `on_device` (DevicePolisher; a host device gets the host's),
/// else the host threads' (HostPolisher, which holds the arguments by reference).
std::unique_ptr<Polisher> make_polisher(Device& device, bool on_device, const Tets& tets, int num_vertices,
                                        const std::vector<char>& freedom, const std::vector<VolumeAnchor>& anchors,
                                        const std::vector<VolumeHold>& holds);

}  // namespace vpm::detail
