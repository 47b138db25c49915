// Mesh resolution and surface -> tets (see tets.hpp), and the public tet helpers of
// vpm/mesh_image.hpp: four-boundary-vertex tets, the TetGen stand-in of a build without TetGen.
#include "image/tets.hpp"

#include <algorithm>
#include <cmath>

#include "image/surface.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/geometry.hpp"
#include "vpm/mesh_order.hpp"
#include "vpm/topology.hpp"

namespace vpm {
namespace detail {

void record(MeshImageReport& report, const std::string& key, const Stopwatch& t0) {
  report.timings.push_back({key, t0.seconds(), t0.cpu_seconds()});
}

// Constants relating the requested vertex count to the surface edge length and TetGen's
// volume bound (calibrated on Colin27, see docs/mesh_image.md):
//   edge = kEdge * (V / N)^(1/3),  max_volume = kVol * V / N.
constexpr double kEdge = 0.98;
constexpr double kVol = 0.47;

Resolution resolution_for(double volume, const MeshImageOptions& o) {
  Resolution r;
  if (o.max_volume > 0) {
    r.max_volume = o.max_volume;
    r.edge = kEdge * std::cbrt(o.max_volume / kVol);
  } else {
    if (o.target_vertices < 10)
      throw MeshImageError(MeshImageError::Problem::kTooFewTargetVertices, std::to_string(o.target_vertices),
                           "target_vertices " + std::to_string(o.target_vertices) + ": need at least 10");
    r.edge = kEdge * std::cbrt(volume / o.target_vertices);
    r.max_volume = kVol * volume / o.target_vertices;
  }
  return r;
}

namespace {

// Sizes, boundary, dihedral range and volumes of the TetGen mesh of `s`.
MeshImageReport::Mesh mesh_stats(const TetMesh& mesh, const TriSurface& s, const TetgenInfo& tinfo) {
  MeshImageReport::Mesh m;
  const Triangles bf = boundary_faces(mesh.tets);
  const auto on_b = boundary_vertex_mask(mesh.num_vertices(), bf);
  const auto dih = dihedral_angles_deg(mesh.vertices, mesh.tets);
  const auto btopo = surface_topology(mesh.num_vertices(), bf);
  m.vertices = mesh.num_vertices();
  m.tets = mesh.num_tets();
  m.boundary_vertices = int(std::count(on_b.begin(), on_b.end(), 1));
  m.boundary_faces = int(bf.rows());
  m.boundary_euler = btopo.euler;
  m.min_dihedral_deg = dih.size() ? dih.minCoeff() : 0.0;
  m.max_dihedral_deg = dih.size() ? dih.maxCoeff() : 0.0;
  m.four_boundary_vertex_tets = tinfo.four_boundary_vertex_tets;
  m.interior_points_added = tinfo.interior_points_added;
  m.edge_splits = tinfo.edge_splits;
  m.volume_mm3 = tet_volumes(mesh.vertices, mesh.tets).sum();
  m.surface_volume_mm3 = enclosed_volume(s);
  return m;
}

}  // namespace

TetMesh surface_to_tets(const TriSurface& raw, const Resolution& res, const MeshImageOptions& o,
                        MeshImageReport& report, const std::string& source) {
  Stopwatch t0;
  if (o.progress) o.progress("remeshing the surface to edge " + format_sig(res.edge, 3) + " mm");
  TriSurface s;
  RemeshInfo info;
  try {
    s = remesh_surface(raw, res.edge, o.remesh_iterations, &info);
  } catch (const MeshImageError& e) {
    throw MeshImageError(e.problem(), source + ": " + e.context(), source + ": " + e.what());
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
  record(report, "remesh", t0);
  report.parameters.edge_mm = info.edge_length;
  report.parameters.remesh_retries = info.retries;
  if (o.progress && info.retries)
    o.progress("remeshed again " + std::to_string(info.retries) + " time(s) with a shorter edge (" +
               format_sig(info.edge_length, 3) + " mm): the first surface self-intersected");
  check_closed_genus0(s, source, "the remeshed surface");
  report.surface = surface_stats(s);

  t0.restart();
  TetgenOptions to;
  to.radius_edge = o.radius_edge;
  to.min_dihedral_deg = o.min_dihedral_deg;
  to.max_volume = res.max_volume;
  if (o.progress) o.progress("tetrahedralising (TetGen)");
  TetgenInfo tinfo;
  TetMesh mesh = tetrahedralize_surface(s, to, &tinfo);
  sort_spatially(mesh);  // TetGen's numbering scatters neighbours in memory (vpm/mesh_order.hpp)
  record(report, "tetgen", t0);
  report.parameters.tetgen_switches = tinfo.switches;
  report.mesh = mesh_stats(mesh, s, tinfo);
  return mesh;
}

}  // namespace detail

int count_four_boundary_vertex_tets(const TetMesh& mesh) {
  const Triangles bf = boundary_faces(mesh.tets);
  const auto on_b = boundary_vertex_mask(mesh.num_vertices(), bf);
  int n = 0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    n += on_b[mesh.tets(t, 0)] && on_b[mesh.tets(t, 1)] && on_b[mesh.tets(t, 2)] && on_b[mesh.tets(t, 3)];
  return n;
}

#if !VPM_HAVE_TETGEN
TetMesh tetrahedralize_surface(const TriSurface&, const TetgenOptions&, TetgenInfo*) {
  throw InputError("mesh-image: this vpm was built without TetGen (tetrahedralisation unavailable)");
}
#endif

}  // namespace vpm
