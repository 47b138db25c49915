#pragma once
// Canonical volume elements of the unit ball (paper 6.2; docs/collective.md): radial shells,
// each cut by a level of the icosahedral subdivision of the sphere (vpm/icosphere.hpp,
// 20 * 4^l spherical triangles), every element of the same volume. Two layouts:
//  * shells: the level-L triangles in each of K shells at equal-volume radii r_k = (k / K)^(1/3)
//    (the paper's scheme; the inner shells' elements are long thin cones);
//  * graded: near-cubic elements everywhere: level L at the surface, one level coarser each time
//    the radius halves, as many shells per level as keep the elements about as thick as wide
//    (0.35 to 2.8 times: equal volumes make the ratio go as r^-3 within a level); K follows from L.
// Element id = offset(shell) + triangle (the triangle's index at its shell's level). Each element
// has S sample points, uniform in volume (area-uniform on the spherical triangle by Arvo's method,
// r^3 uniform in the shell), from a fixed low-discrepancy sequence: the same points for every
// subject, so every subject's feature of an element is computed from the same number of samples
// at the same places of the ball.
#include <Eigen/Core>
#include <array>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "vpm/json.hpp"
#include "vpm/mesh.hpp"

namespace vpm {

namespace detail {
struct ElementArrays;  // host/collective/element_arrays.hpp: what the sample generator reads
}

/// What fixes an element set. Tables computed with different definitions must never be mixed:
/// compare definitions with ==, and record them with to_json.
enum class ElementLayout {
  shells,  ///< level L in each of K equal-volume shells
  graded,  ///< near-cubic elements: the level falls by one each time the radius halves; K from L
};
/// "shells", "graded"; InputError otherwise.
ElementLayout parse_element_layout(const std::string& name);
const char* to_string(ElementLayout layout);

struct ElementDefinition {
  int level = 3;     ///< icosphere subdivisions L (0..7) of the outermost shell
  int shells = 8;    ///< radial shells K (1..256); graded: set by graded_shells(level)
  int samples = 64;  ///< sample points S per element (1..4096)
  ElementLayout layout = ElementLayout::shells;
  /// Version of the sample generator; bumped whenever the sample points would change.
  static constexpr int kGeneratorVersion = 1;
  /// Spherical triangles T = 20 * 4^level of the outermost shell (no elements are built).
  int triangles() const { return 20 << (2 * level); }
  /// All elements: the sum of the shells' triangle counts (no elements are built).
  int elements() const;
  bool operator==(const ElementDefinition& o) const {
    return level == o.level && shells == o.shells && samples == o.samples && layout == o.layout;
  }
  bool operator!=(const ElementDefinition& o) const { return !(*this == o); }
};
/// "level/shells/samples layout", e.g. "6/41/8 graded": how messages name a definition.
std::string to_string(const ElementDefinition& definition);

/// The triangle level of each shell of `definition`, innermost first (K entries, nondecreasing,
/// the last one `level`). shells: K times L. graded: from the outside in, radii r with
/// 2^-(j+1/2) < r <= 2^-(j-1/2) get level L - j (level 0 takes the rest), each band as many shells
/// as make its elements' volume closest to a cube of the level-L triangle's width at r = 1
/// (at least one).
std::vector<int> shell_levels(const ElementDefinition& definition);

/// The shell count K of the graded layout at `level` (9 at level 3, 16 at level 4).
int graded_shells(int level);

/// {"level", "shells", "samples", "layout", "generator": "icosphere-arvo-r3", "generator_version"}
Json to_json(const ElementDefinition& definition);

/// Reads a definition written by to_json (no "layout": shells, as written before graded existed);
/// InputError naming `source` if a field is missing or out of range, if a graded definition's
/// shells differ from graded_shells(level), or if the generator version differs from this build's.
ElementDefinition element_definition_from_json(const Json& json, const std::string& source);

/// Spread of the element volumes (ball volume 4 pi / 3 split into size() elements).
struct ElementVolumeStats {
  double mean = 0, min = 0, max = 0;
  double std_relative = 0;  ///< standard deviation / mean
};

class CanonicalElements {
 public:
  /// Builds the elements of `definition`; InputError when a field is out of range (or a graded
  /// definition's shells are not graded_shells(level)).
  explicit CanonicalElements(const ElementDefinition& definition = {});

  const ElementDefinition& definition() const { return def_; }
  int size() const { return offset_.back(); }
  /// Triangles of the outermost shell, 20 * 4^level.
  int triangles() const { return static_cast<int>(sphere_.triangles.rows()); }
  /// Triangle level of shell k (shell_levels(definition())[k]).
  int shell_level(int k) const { return shell_level_[k]; }
  /// Triangles (elements) of shell k, 20 * 4^shell_level(k).
  int shell_triangles(int k) const { return offset_[k + 1] - offset_[k]; }
  int shell_of(int id) const;
  /// The element's triangle at its shell's level.
  int triangle_of(int id) const { return id - offset_[shell_of(id)]; }
  int id(int shell, int triangle) const { return offset_[shell] + triangle; }
  /// The element of shell k over triangle t of the outermost level (sphere()): its ancestor at
  /// the shell's level (children of triangle f are 4f..4f+3 at every level).
  int id_over(int shell, int fine_triangle) const {
    return offset_[shell] + (fine_triangle >> (2 * (def_.level - shell_level_[shell])));
  }

  /// The spherical triangulation (unit sphere, outward triangles): icosphere(level).
  const TriSurface& sphere() const { return sphere_; }
  /// icosphere(l) for l = 0..level.
  const TriSurface& sphere(int l) const { return levels_[l]; }
  /// Inner radius of shell k (k = 0..K; radius(K) = 1).
  double radius(int k) const;
  /// The radius halving shell k's volume: cbrt((radius(k)^3 + radius(k + 1)^3) / 2).
  double mid_radius(int k) const;
  /// Element `id`'s centre: the direction of its triangle's centroid at its shell's mid_radius.
  Eigen::Vector3d centre(int id) const;
  /// Exact volume of element `id`: solid angle of its triangle x (r_{k+1}^3 - r_k^3) / 3.
  double volume(int id) const;
  ElementVolumeStats volume_stats() const;

  /// Element ids sharing a face with `id`: the three edge-adjacent triangles of its shell, and in
  /// the shells inside and outside it (when they exist) the elements over or under its triangle
  /// (one at the same or a coarser level, 4^d at a level d finer). Symmetric.
  std::vector<int> neighbours(int id) const;

  /// The sample points of every element: row id * S + s, S = definition().samples (ball
  /// coordinates). The same for every call and every machine. Made on the first call and kept
  /// (size() * S * 24 bytes: 416 MB at level 6 graded with 8 samples); code that visits the
  /// samples once makes them as it goes instead (sample(); vpm/element_sampler.hpp).
  const Points& samples() const;
  /// Sample point s (0 <= s < S) of element `id`: row id * S + s of samples(), bit for bit, made
  /// on its own by the generator the device's kernels run too (kernels/element_samples.clh).
  Eigen::Vector3d sample(int id, int s) const;
  /// The generator's arrays (private: host/collective/element_arrays.hpp), shared by copies.
  const detail::ElementArrays& arrays() const { return *arrays_; }

  /// Every element's neighbours(id) in one table (compressed rows), built on the first call
  /// (thread-safe; shared by copies): the loops over every element's neighbours (shrinkage,
  /// smoothing, clusters) read it without allocating.
  struct Adjacency {
    std::vector<int> offset, list;  ///< element e's neighbours are list[offset[e] .. offset[e + 1])
    std::span<const int> of(int e) const {
      const size_t i = static_cast<size_t>(e);
      return {list.data() + offset[i], static_cast<size_t>(offset[i + 1] - offset[i])};
    }
  };
  const Adjacency& adjacency() const;
  /// adjacency().of(id)
  std::span<const int> adjacent(int id) const { return adjacency().of(id); }

  /// The element containing ball point `p` (|p| <= 1; points on a boundary go to one side),
  /// or -1 when |p| > 1 + 1e-9.
  int element_of(const Eigen::Vector3d& p) const;

 private:
  void make_arrays();

  ElementDefinition def_;
  TriSurface sphere_;
  std::vector<TriSurface> levels_;  // icosphere(0..level): triangle f of level l has children 4f..4f+3
  std::vector<int> shell_level_;    // per shell
  std::vector<int> offset_;         // first id of each shell, and size() last
  std::vector<double> radius3_;     // r_k^3, k = 0..K
  std::vector<std::vector<double>> solid_angle_;     // per level, per triangle
  std::vector<std::vector<int>> edge_neighbours_;    // per level: 3 per triangle, across its edges
  std::shared_ptr<const detail::ElementArrays> arrays_;  // the generator's arrays, samples() once made
  struct Lazy {  // the adjacency, made on first use
    std::once_flag adjacency_once;
    Adjacency adjacency;
  };
  std::shared_ptr<Lazy> lazy_;
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
