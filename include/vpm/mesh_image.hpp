#pragma once
// Image mask (or closed surface) -> quality tetrahedral mesh, the `vpm mesh-image` pipeline:
//
//   mask (value > threshold, largest component, cavities filled)
//   -> Gaussian smoothing (sigma = `smooth` mm) and resampling on a grid of 0.7 x the
//      target edge length
//   -> topology check (Euler characteristic of the mask surface); handles removed by
//      morphological closing at growing radii, or refused (InputError) when that fails
//   -> marching tetrahedra (Freudenthal cube split: always a closed 2-manifold)
//   -> isotropic remeshing to the target edge length + angle smoothing (CGAL PMP, GPL)
//   -> TetGen (AGPL) with radius-edge / dihedral bounds and a max volume; tets whose four
//      vertices are all on the boundary are removed by inserting interior points
//   -> optional atlas labels: per tet the atlas label at the centroid, per vertex the
//      majority label of its tets (fields "label", integer).
//
// Coordinates are world millimetres (NIfTI sform/qform). Report keys are listed at
// mesh_image().
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh.hpp"
#include "vpm/mesh_image_report.hpp"

namespace vpm {

struct MeshImageOptions {
  /// Mask = voxels with value > threshold.
  double threshold = 0.0;
  /// When not empty, the mask is instead the voxels whose value, rounded to an integer, is one
  /// of these labels (one structure, or several, of a label image such as an atlas or a
  /// segmentation); `threshold` is then ignored.
  std::vector<int> select_labels;
  /// Target number of mesh vertices (the paper's brain has about 5,200). Ignored when
  /// max_volume > 0.
  int target_vertices = 5200;
  /// Largest tet volume in mm^3 (TetGen -a). When > 0 it sets the resolution instead of
  /// target_vertices.
  double max_volume = 0.0;
  /// Gaussian smoothing of the mask before surface extraction, sigma in mm; < 0 chooses
  /// 0.5 x the target edge length (at least 2 voxels), 0 disables smoothing.
  double smooth = -1.0;
  /// TetGen quality bounds: radius-edge ratio and smallest dihedral angle (degrees), as in -q1.5/12.
  double radius_edge = 1.5;
  double min_dihedral_deg = 12.0;
  /// Largest closing radius (in extraction-grid cells) tried to remove handles of the mask.
  int max_closing_radius = 6;
  /// Isotropic remeshing iterations.
  int remesh_iterations = 5;
  /// A mask touching the image border is refused (InputError) unless this is set; then the
  /// surface is closed just outside the image (a flat cap), e.g. a brainstem cut by the field
  /// of view.
  bool close_at_border = false;
  /// Surface inputs only: when > 0, the surface is not remeshed itself; the solid it encloses
  /// is rasterised on voxels of this size (vpm/voxelize.hpp: winding numbers, so triangles that
  /// cross each other are fine) and that mask is meshed like an image. For surfaces that
  /// self-intersect (many public models do) or are too detailed to remesh.
  double voxelize_mm = 0;
  /// Progress messages (stage names); may be empty.
  std::function<void(const std::string&)> progress;
};

/// An input that the mesh-image settings cannot mesh, with the setting that would help.
/// what() is the full message in library terms (field names of MeshImageOptions); context()
/// is the fact alone, so that a caller can name its own controls for the remedy.
class MeshImageError : public InputError {
 public:
  enum class Problem {
    kTooFewTargetVertices,  ///< target_vertices < 10; context: the value
    kAtlasWithSurface,      ///< an atlas given with a surface input; context: the surface path
    kMaskTouchesBorder,     ///< mask on the image border without close_at_border; context: the
                            ///< message up to the remedy (image, voxel, world position)
    kMaskVanishes,          ///< smoothing removed the whole mask; context: the message up to the
                            ///< remedy (image, sigma)
    kSurfaceSelfIntersects, ///< triangles of the input (or remeshed) surface cross; context: the
                            ///< message up to the remedy (how many pairs, where)
  };
  MeshImageError(Problem problem, std::string context, const std::string& message);
  Problem problem() const { return problem_; }
  const std::string& context() const { return context_; }

 private:
  Problem problem_;
  std::string context_;
};

/// Meshes the mask of `image` (voxels > options.threshold). When `atlas` is given, it must be
/// on the same grid (dims and affine within 1e-3 mm; else InputError) and labels are attached:
/// cell field "label" = atlas label at each tet's centroid (nearest voxel, through the atlas's
/// own affine; 0 outside), point field "label" = majority label of the vertex's tets.
///
/// `report` (if given) receives the input, the parameters chosen, the topology repairs, the
/// extracted and remeshed surfaces, the mesh quality, the label volumes (with an atlas) and
/// the stage times mask, grid, topology, extract, remesh, tetgen, labels, total
/// (vpm/mesh_image_report.hpp; to_json() gives the report file).
///
/// Throws InputError for an empty mask, an atlas on another grid, MeshImageError for a mask
/// touching the image border (without close_at_border) or vanishing after smoothing, or a mask whose handles cannot be closed (genus > 0 after the largest closing radius);
/// NumericalError when TetGen fails on the remeshed surface.
TetMesh mesh_image(const Image& image, const MeshImageOptions& options, MeshImageReport* report = nullptr,
                   const Image* atlas = nullptr);

/// Reads `image_path` (NIfTI) or a closed surface (.off/.obj/.stl) and meshes it; with
/// `labels_path` non-empty reads that atlas and labels the mesh (MeshImageError
/// kAtlasWithSurface for a surface input). Same report as above, plus timings_s.read.
TetMesh mesh_image_file(const std::string& image_path, const MeshImageOptions& options,
                        MeshImageReport* report = nullptr, const std::string& labels_path = "");

/// Meshes the solid bounded by a closed, oriented, genus-0 triangle surface (world mm):
/// isotropic remeshing, then TetGen, as above. InputError if the surface is open,
/// non-manifold, disconnected or of higher genus. `report` as above, with image_input false.
TetMesh mesh_surface(const TriSurface& surface, const MeshImageOptions& options,
                     MeshImageReport* report = nullptr, const std::string& source = "surface");

// ---- building blocks (exposed for tests and benchmarks) --------------------------------

/// Attaches "label" cell and point fields from `atlas` (see mesh_image). Returns, per label
/// found (0 included), tets and volume_mm3 (voxels fields left 0).
std::map<int, LabelVolume> label_mesh(TetMesh& mesh, const Image& atlas);

/// A remeshed surface that self-intersects (isotropic remeshing pulls the two sides of a gap
/// narrower than about an edge across each other: 2 of 60 synthetic cohort brains at 45,000
/// vertices) is remeshed again from the input with the edge times kRemeshEdgeShrink, at most
/// kRemeshRetries times (a slightly finer surface resolves the gap; docs/mesh_image.md).
constexpr double kRemeshEdgeShrink = 0.95;
constexpr int kRemeshRetries = 3;

/// What remesh_surface did: the edge length of the surface it returned, and how many shorter
/// retries it took to get a surface that does not self-intersect (0: the first).
struct RemeshInfo {
  double edge_length = 0;
  int retries = 0;
};

/// Isotropic remeshing of a closed manifold surface to `edge_length` (CGAL
/// Polygon_mesh_processing::isotropic_remeshing, then angle-and-area smoothing), keeping its
/// topology; retried with shorter edges as above when the result self-intersects (`info`, when
/// given, says what ran). Throws InputError when vpm was built without CGAL, and
/// MeshImageError (kSurfaceSelfIntersects) when the surface, or the last retry's remeshed
/// surface, self-intersects (how many triangle pairs cross, the first pair and where).
TriSurface remesh_surface(const TriSurface& surface, double edge_length, int iterations,
                          RemeshInfo* info = nullptr);

/// Smallest and largest triangle angles of a surface, degrees.
std::pair<double, double> triangle_angle_range_deg(const TriSurface& surface);

/// TetGen options for tetrahedralize_surface().
struct TetgenOptions {
  double radius_edge = 1.5;
  double min_dihedral_deg = 12.0;
  double max_volume = 0.0;      ///< mm^3; 0 = no bound
  bool preserve_surface = true; ///< -Y: no Steiner points on the boundary
  int fix_rounds = 0;           ///< rounds of interior point insertion against four-boundary-vertex tets
};

/// What tetrahedralize_surface() did.
struct TetgenInfo {
  std::string switches;               ///< TetGen command-line switches used, e.g. "pq1.5/12a2.1YzQ"
  int fix_rounds = 0;                 ///< rounds of interior point insertion run
  int edge_splits = 0;                ///< interior edges split afterwards
  int interior_points_added = 0;      ///< points inserted over all rounds
  int four_boundary_vertex_tets = 0;  ///< such tets left at the end
};

/// Tetrahedralises the solid bounded by a closed surface with TetGen (linked as a library);
/// then, for up to `fix_rounds`, inserts the centroids of tets whose four vertices all lie on
/// the boundary and re-meshes, then splits the longest interior edge of any such tet left
/// (midpoint). `info` (if given) receives what was done. Throws NumericalError if TetGen fails
/// (e.g. a self-intersecting surface) and InputError when vpm was built without TetGen.
TetMesh tetrahedralize_surface(const TriSurface& surface, const TetgenOptions& options,
                               TetgenInfo* info = nullptr);

/// Number of tets whose four vertices are all boundary vertices.
int count_four_boundary_vertex_tets(const TetMesh& mesh);

}  // namespace vpm
