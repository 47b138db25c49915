#pragma once
// Point location in a tet mesh: which tet holds a point, and where (barycentric coordinates);
// and on a triangulation of the unit sphere: which face holds a direction.
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

/// Where a direction lies on a triangulation of the unit sphere.
struct SphereLocation {
  int face = -1;                  ///< the face whose cone from the centre holds the direction
  double bary[3] = {0, 0, 0};     ///< barycentric coordinates on the face's chord triangle
};

/// Locates directions on a fold-free triangulation of the unit sphere (a closed surface mapped by
/// vpm::map_to_sphere or registered on the sphere): the faces' cones from the centre tile space,
/// and a direction p lies in the cone of (a, b, c) when p.(a x b), p.(b x c), p.(c x a) are all
/// non-negative; the coordinates are those of the point where the ray through p crosses the chord
/// triangle (proportional to p.(b x c), p.(c x a), p.(a x b)). Built once (the faces across each
/// edge; a cube map of the directions with about four faces a cell), each query walks across the
/// edges whose plane separates p from the face, from a hint or from a face of p's cell, and scans
/// all faces when the walk does not end (a triangulation with flipped faces).
class SphereLocator {
 public:
  /// `sphere` n x 3 (unit vectors, outward-oriented faces), `faces` m x 3 (indices checked:
  /// InputError otherwise). Both are copied.
  SphereLocator(const Points& sphere, const Triangles& faces);
  /// Location of the direction `p` (any length > 0); `hint` a face near p, or -1.
  SphereLocation locate(const Eigen::Vector3d& p, int hint = -1) const;
  /// Locations of `points` (k x 3), each query starting from the previous result; on the host
  /// threads.
  std::vector<SphereLocation> locate_all(const Points& points) const;
  const Points& vertices() const { return x_; }
  const Triangles& faces() const { return f_; }

 private:
  int cell_of(const Eigen::Vector3d& p) const;
  bool inside(int face, const Eigen::Vector3d& p, double* s) const;
  Points x_;
  Triangles f_;
  std::vector<int> across_;  // 3 per face: the face across the edge (corner k, corner k + 1)
  std::vector<int> cells_;   // 6 n^2 cube-map cells: a face whose centroid is in the cell, or -1
  int n_ = 1;
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
