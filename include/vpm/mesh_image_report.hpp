#pragma once
// What mesh_image() / mesh_surface() / mesh_image_file() report: input, parameters chosen,
// topology repairs, surface and mesh quality, atlas label volumes, timings.
#include <array>
#include <map>
#include <string>
#include <vector>

#include "vpm/json.hpp"

namespace vpm {

/// Size and quality of a triangle surface.
struct SurfaceStats {
  int vertices = 0;
  int triangles = 0;
  int euler = 0;               ///< Euler characteristic
  double mean_edge_mm = 0;     ///< mean edge length
  double min_angle_deg = 0;    ///< smallest triangle angle
  double max_angle_deg = 0;    ///< largest triangle angle
};

/// One morphological closing tried against handles of the mask.
struct ClosingRepair {
  int closing_radius_cells = 0;
  double closing_radius_mm = 0;
  int euler_before = 0;  ///< Euler characteristic before this closing
  int euler_after = 0;   ///< and after it
};

/// Per-label volumes of a labelled mesh (label_mesh), with the atlas's own voxel counts when
/// produced by mesh_image().
struct LabelVolume {
  double tets = 0;              ///< tets carrying the label
  double volume_mm3 = 0;        ///< their summed volume
  double voxels = 0;            ///< atlas voxels with the label (mesh_image only)
  double voxel_volume_mm3 = 0;  ///< their volume (mesh_image only)
};

/// Wall and process CPU seconds of one pipeline stage.
struct StageTime {
  std::string stage;  ///< read, (voxelize,) mask, grid, topology, extract, remesh, tetgen, labels, total
  double wall_s = 0;
  double cpu_s = 0;
};

struct MeshImageReport {
  /// True for an image input (mesh_image); false for a surface input (mesh_surface): then only
  /// input.path, input.volume_mm3, parameters.{target_edge_mm, max_volume_mm3,
  /// tetgen_switches}, surface, mesh and timings are set.
  bool image_input = true;

  struct Input {
    std::string path;              ///< file path, or "image" / the source name
    std::array<int, 3> dims{};     ///< voxels per axis
    std::array<double, 3> spacing_mm{};
    std::string affine_source;     ///< sform, qform or pixdim
    double threshold = 0;          ///< mask = value > threshold (when no labels are selected)
    std::vector<int> select_labels;  ///< mask = these labels (empty: threshold)
    double mask_voxels = 0;        ///< after keeping the largest component and filling cavities
    double mask_volume_mm3 = 0;
    int components_removed = 0;    ///< smaller 6-connected components dropped
    int cavities_filled = 0;
    double border_voxels = 0;      ///< mask voxels on the image border (close_at_border)
    double volume_mm3 = 0;         ///< surface input: enclosed volume
  } input;

  struct Parameters {
    double target_edge_mm = 0;     ///< surface edge length aimed at
    double edge_mm = 0;            ///< the remeshed surface's edge length (shorter after retries)
    int remesh_retries = 0;        ///< shorter remeshings after self-intersecting ones (remesh_surface)
    double grid_mm = 0;            ///< extraction grid step (image input)
    double smooth_sigma_mm = 0;    ///< Gaussian sigma used (image input)
    double max_volume_mm3 = 0;     ///< TetGen volume bound
    std::string tetgen_switches;
    double voxelize_mm = 0;        ///< surface input meshed through a voxel mask of this size (0: no)
  } parameters;

  /// Topology of the extracted mask surface and the closings that made it genus 0 (image input).
  struct Topology {
    std::vector<ClosingRepair> repairs;
    int euler_before = 0;
    int genus_before = 0;
    int grid_components_removed = 0;  ///< on the extraction grid (14-connectivity)
    int grid_cavities_filled = 0;
    int closing_radius_cells = 0;     ///< 0: no closing needed
    int euler = 0;                    ///< after the repairs (2)
  } topology;

  SurfaceStats extracted_surface;           ///< marching tetrahedra output (image input)
  double extracted_surface_volume_mm3 = 0;  ///< its enclosed volume
  SurfaceStats surface;                     ///< after remeshing

  /// The tet mesh.
  struct Mesh {
    int vertices = 0;
    int tets = 0;
    int boundary_vertices = 0;
    int boundary_faces = 0;
    int boundary_euler = 0;
    double min_dihedral_deg = 0;
    double max_dihedral_deg = 0;
    int four_boundary_vertex_tets = 0;  ///< left after the fixes (0 expected)
    int interior_points_added = 0;      ///< centroids inserted against them
    int edge_splits = 0;                ///< interior edges split against them
    double volume_mm3 = 0;
    double surface_volume_mm3 = 0;      ///< enclosed by the remeshed surface
  } mesh;

  /// Non-zero atlas labels (with an atlas only).
  bool has_labels = false;
  std::map<int, LabelVolume> labels;

  /// Stage times in the order the stages ran ("read" last, from mesh_image_file).
  std::vector<StageTime> timings;
};

/// The report as JSON: "input", "timings_s" / "cpu_s" {stage: seconds}, "parameters",
/// "topology", "extracted_surface" (with volume_mm3), "surface", "mesh", "labels" {label:
/// {tets, volume_mm3, voxels, voxel_volume_mm3}}; keys of an image input in the order the
/// stages fill them, a surface input's subset as listed at MeshImageReport::image_input.
Json to_json(const MeshImageReport& report);

/// {vertices, triangles, euler, mean_edge_mm, min_angle_deg, max_angle_deg}.
Json to_json(const SurfaceStats& stats);

}  // namespace vpm
