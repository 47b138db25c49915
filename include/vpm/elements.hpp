#pragma once
// Canonical volume elements of the unit ball (paper 6.2; docs/collective.md): the level-L
// icosahedral subdivision of the sphere (vpm/icosphere.hpp, 20 * 4^L spherical triangles) times
// K radial shells at equal-volume radii r_k = (k / K)^(1/3). Element id = shell * T + triangle
// (T = 20 * 4^L triangles). Each element has S sample points, uniform in volume (area-uniform on
// the spherical triangle by Arvo's method, r^3 uniform in the shell), from a fixed
// low-discrepancy sequence: the same points for every subject, so every subject's feature of an
// element is computed from the same number of samples at the same places of the ball.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "vpm/json.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

/// What fixes an element set. Tables computed with different definitions must never be mixed:
/// compare definitions with ==, and record them with to_json.
struct ElementDefinition {
  int level = 3;     ///< icosphere subdivisions L (0..7)
  int shells = 8;    ///< radial shells K (1..256)
  int samples = 64;  ///< sample points S per element (1..4096)
  /// Version of the sample generator; bumped whenever the sample points would change.
  static constexpr int kGeneratorVersion = 1;
  /// Spherical triangles T = 20 * 4^level (no elements are built).
  int triangles() const { return 20 << (2 * level); }
  /// Elements T * shells; element id = shell * T + triangle.
  int elements() const { return triangles() * shells; }
  bool operator==(const ElementDefinition& o) const {
    return level == o.level && shells == o.shells && samples == o.samples;
  }
  bool operator!=(const ElementDefinition& o) const { return !(*this == o); }
};

/// {"level", "shells", "samples", "generator": "icosphere-arvo-r3", "generator_version"}
Json to_json(const ElementDefinition& definition);

/// Reads a definition written by to_json; InputError naming `source` if a field is missing or
/// out of range, or if the generator version differs from this build's.
ElementDefinition element_definition_from_json(const Json& json, const std::string& source);

/// Spread of the element volumes (ball volume 4 pi / 3 split into size() elements).
struct ElementVolumeStats {
  double mean = 0, min = 0, max = 0;
  double std_relative = 0;  ///< standard deviation / mean
};

class CanonicalElements {
 public:
  /// Builds the elements of `definition`; InputError when a field is out of range.
  explicit CanonicalElements(const ElementDefinition& definition = {});

  const ElementDefinition& definition() const { return def_; }
  int size() const { return triangles() * def_.shells; }
  int triangles() const { return static_cast<int>(sphere_.triangles.rows()); }
  int shell_of(int id) const { return id / triangles(); }
  int triangle_of(int id) const { return id % triangles(); }
  int id(int shell, int triangle) const { return shell * triangles() + triangle; }

  /// The spherical triangulation (unit sphere, outward triangles): icosphere(level).
  const TriSurface& sphere() const { return sphere_; }
  /// Inner radius of shell k (k = 0..K; radius(K) = 1).
  double radius(int k) const;
  /// The radius halving shell k's volume: cbrt((radius(k)^3 + radius(k + 1)^3) / 2).
  double mid_radius(int k) const;
  /// Element `id`'s centre: the direction of its triangle's centroid at its shell's mid_radius.
  Eigen::Vector3d centre(int id) const;
  /// Exact volume of element `id`: solid angle of its triangle x (r_{k+1}^3 - r_k^3) / 3.
  double volume(int id) const;
  ElementVolumeStats volume_stats() const;

  /// Element ids sharing a face with `id`: the three edge-adjacent triangles of its shell, and
  /// the same triangle in the shells inside and outside it (when they exist). Symmetric.
  std::vector<int> neighbours(int id) const;

  /// The sample points of every element: row id * S + s, S = definition().samples (ball
  /// coordinates). The same for every call and every machine.
  const Points& samples() const { return samples_; }

  /// The element containing ball point `p` (|p| <= 1; points on a boundary go to one side),
  /// or -1 when |p| > 1 + 1e-9.
  int element_of(const Eigen::Vector3d& p) const;

 private:
  ElementDefinition def_;
  TriSurface sphere_;
  std::vector<TriSurface> levels_;  // icosphere(0..level): triangle f of level l has children 4f..4f+3
  std::vector<double> solid_angle_;
  std::vector<int> edge_neighbours_;  // 3 per triangle: the triangles across its edges
  Points samples_;
};

/// Writes the element table of `elements`: a TSV at `tsv_path` with a header line and one row per
/// element, `element shell triangle volume centre_x centre_y centre_z` (centre: the direction of
/// the triangle's centroid at the radius halving the shell's volume), and beside it a JSON
/// sidecar (the path with .tsv replaced by .json, else .json appended) holding the definition,
/// the element count, the volume statistics and the column descriptions. Both files are written
/// under temporary names and renamed; InputError naming the path when one cannot be written.
void write_element_table(const std::string& tsv_path, const CanonicalElements& elements);

/// The sidecar path of a table: "a/b.tsv" -> "a/b.json"; any other name gets ".json" appended.
std::string sidecar_path(const std::string& table_path);

}  // namespace vpm
