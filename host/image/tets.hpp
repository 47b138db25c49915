#pragma once
// Mesh resolution and the surface -> tets step of the image layer (remeshing through
// host/with_cgal, TetGen through host/with_tetgen, mesh quality into the report).
#include <string>

#include "vpm/mesh.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/timing.hpp"

namespace vpm::detail {

/// Appends stage `key` with the wall and process CPU seconds of `t0` to report.timings.
void record(MeshImageReport& report, const std::string& key, const Stopwatch& t0);

/// Surface edge length and TetGen volume bound for a mesh of the requested density.
struct Resolution {
  double edge = 0, max_volume = 0;
};

/// Resolution for a solid of `volume` mm^3: from options.max_volume when > 0, else from
/// options.target_vertices (MeshImageError kTooFewTargetVertices when < 10).
Resolution resolution_for(double volume, const MeshImageOptions& options);

/// Remeshes `raw` to res.edge, checks it is closed genus 0, runs TetGen with the options'
/// bounds and fills report.surface, .mesh, .parameters.tetgen_switches and the timings
/// remesh, tetgen. `source` names the input in error messages.
TetMesh surface_to_tets(const TriSurface& raw, const Resolution& res, const MeshImageOptions& options,
                        MeshImageReport& report, const std::string& source);

}  // namespace vpm::detail
