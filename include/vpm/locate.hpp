#pragma once
// Point location in a tet mesh: which tet holds a point, and where (barycentric coordinates).
// The same walk-then-grid search the volume map uses on the device (kernels/moser.cl), here as
// a host service for analysis (label sampling, transfer of fields between meshes).
#include <Eigen/Core>
#include <memory>
#include <vector>

#include "vpm/mesh.hpp"
#include "vpm/topology.hpp"

namespace vpm {

/// Where a point lies in a mesh.
struct Location {
  int tet = -1;            ///< containing tet (or the nearest one found for outside points)
  double bary[4] = {0, 0, 0, 0};  ///< barycentric coordinates in `tet`, clamped to [0, 1]
  /// Smallest unclamped barycentric coordinate: >= -1e-12 inside the tet, negative outside
  /// (about -distance / tet height).
  double min_bary = 0;
  bool inside() const { return min_bary >= -1e-9; }
};

/// Locates points in a fixed tet mesh. Built once (O(m): per-tet inverse edge matrices, face
/// neighbours and a uniform grid of about one cell per tet), then each query walks through face
/// neighbours from a hint tet and falls back to the grid cell of the point.
class TetLocator {
 public:
  /// `vertices` n x 3, `tets` m x 4 (non-degenerate). Both are copied.
  TetLocator(const Points& vertices, const Tets& tets);
  /// The same with the mesh's topology (tet_topology of `tets`) given: a mesh that moves, located
  /// again and again, sorts its faces once.
  TetLocator(const Points& vertices, const Tets& tets, const TetTopology& topology);
  ~TetLocator();
  TetLocator(TetLocator&&) noexcept;
  TetLocator& operator=(TetLocator&&) noexcept;

  /// Location of `p`; `hint` is a tet near p (e.g. the previous query's), or -1.
  Location locate(const Eigen::Vector3d& p, int hint = -1) const;
  /// Locations of `points` (k x 3), each query starting from the previous result (so nearby
  /// consecutive points are cheap). Runs on the host threads available.
  std::vector<Location> locate_all(const Points& points) const;
  /// The tets located in (m x 4) and their vertices (n x 3).
  const Tets& tets() const;
  const Points& vertices() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Points carried from one embedding of a tet mesh to another: each of `points` (k x 3) is
/// located in the mesh at `from` (n x 3, with `tets`) and mapped to the same barycentric
/// combination of the vertices at `to` (n x 3), e.g. ball points to a subject's native space
/// through its ball map (`to` = the mesh's original_position). Points outside the mesh (the thin
/// gap between an inscribed mesh and the sphere) use the nearest boundary tet's clamped
/// barycentric coordinates. InputError when `from` and `to` differ in rows. Runs on the host
/// threads.
Points pull_back_points(const Points& points, const Points& from, const Tets& tets, const Points& to);
/// The same with the mesh at `from` already prepared: `from` (its locator) and `to` (n x 3).
Points pull_back_points(const Points& points, const TetLocator& from, const Points& to);

}  // namespace vpm
