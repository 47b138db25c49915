// Isotropic surface remeshing with CGAL Polygon_mesh_processing (GPL-3+ parts of CGAL).
// The only translation unit that includes CGAL (it compiles slowly).
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/angle_and_area_smoothing.h>
#include <CGAL/Polygon_mesh_processing/remesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>

#include <string>
#include <vector>

#include "vpm/error.hpp"
#include "vpm/mesh_image.hpp"

namespace vpm {

namespace {
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Mesh = CGAL::Surface_mesh<K::Point_3>;
namespace PMP = CGAL::Polygon_mesh_processing;

// MeshImageError (kSurfaceSelfIntersects) when triangles of `mesh` cross each other: how many pairs, and the first pair with
// a point of it (TetGen cannot mesh such a surface, and has crashed on one).
void refuse_self_intersections(const Mesh& mesh, const std::string& what) {
  if (!PMP::does_self_intersect(mesh)) return;
  std::vector<std::pair<Mesh::Face_index, Mesh::Face_index>> pairs;
  PMP::self_intersections(faces(mesh), mesh, std::back_inserter(pairs));
  std::string where;
  if (!pairs.empty()) {
    const auto p = mesh.point(mesh.target(mesh.halfedge(pairs[0].first)));
    where = " (e.g. triangles " + std::to_string(pairs[0].first.idx()) + " and " +
            std::to_string(pairs[0].second.idx()) + ", near " + std::to_string(p.x()) + ", " + std::to_string(p.y()) +
            ", " + std::to_string(p.z()) + ")";
  }
  const std::string fact = what + " self-intersects: " + std::to_string(pairs.size()) + " pairs of triangles cross" + where;
  throw MeshImageError(MeshImageError::Problem::kSurfaceSelfIntersects, fact,
                       fact + "; MeshImageOptions::voxelize_mm > 0 meshes the solid it encloses instead");
}

// The input as a CGAL mesh; InputError when a triangle cannot be added or the surface is open,
// MeshImageError when it self-intersects.
Mesh to_cgal(const TriSurface& surface) {
  Mesh mesh;
  std::vector<Mesh::Vertex_index> vid(surface.vertices.rows());
  for (int i = 0; i < surface.vertices.rows(); ++i)
    vid[i] = mesh.add_vertex(K::Point_3(surface.vertices(i, 0), surface.vertices(i, 1), surface.vertices(i, 2)));
  for (int f = 0; f < surface.triangles.rows(); ++f) {
    const auto fi = mesh.add_face(vid[surface.triangles(f, 0)], vid[surface.triangles(f, 1)],
                                  vid[surface.triangles(f, 2)]);
    if (fi == Mesh::null_face())
      throw InputError("remesh: triangle " + std::to_string(f) +
                       " cannot be added (non-manifold or inconsistently oriented surface)");
  }
  if (!CGAL::is_closed(mesh)) throw InputError("remesh: the surface is not closed");
  refuse_self_intersections(mesh, "the surface");
  return mesh;
}

// One isotropic remeshing of `mesh` to `edge_length`, then angle smoothing with Delaunay flips
// (lifts the few remaining small angles).
void remesh_once(Mesh& mesh, double edge_length, int iterations) {
  PMP::isotropic_remeshing(faces(mesh), edge_length, mesh,
                           PMP::parameters::number_of_iterations(iterations)
                               .number_of_relaxation_steps(3)
                               .protect_constraints(false));
  PMP::angle_and_area_smoothing(mesh, PMP::parameters::number_of_iterations(3)
                                          .use_area_smoothing(false)
                                          .use_Delaunay_flips(true)
                                          .use_safety_constraints(true));
  mesh.collect_garbage();
}

// `mesh` (garbage collected) as vpm's surface, vertex and face order kept.
TriSurface from_cgal(const Mesh& mesh) {
  TriSurface out;
  out.vertices.resize(mesh.number_of_vertices(), 3);
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    out.vertices.row(v.idx()) << p.x(), p.y(), p.z();
  }
  out.triangles.resize(mesh.number_of_faces(), 3);
  int f = 0;
  for (auto fi : mesh.faces()) {
    int c = 0;
    for (auto v : CGAL::vertices_around_face(mesh.halfedge(fi), mesh)) out.triangles(f, c++) = v.idx();
    ++f;
  }
  return out;
}

}  // namespace

TriSurface remesh_surface(const TriSurface& surface, double edge_length, int iterations, RemeshInfo* info) {
  const Mesh input = to_cgal(surface);
  double edge = edge_length;
  for (int retry = 0;; ++retry, edge *= kRemeshEdgeShrink) {
    Mesh mesh = input;
    remesh_once(mesh, edge, iterations);
    if (!PMP::does_self_intersect(mesh)) {
      if (info) *info = {edge, retry};
      return from_cgal(mesh);
    }
    if (retry == kRemeshRetries)  // throws, naming the crossing triangles
      refuse_self_intersections(mesh, "the remeshed surface (edge " + std::to_string(edge) + " after " +
                                          std::to_string(retry) +
                                          " shorter retries; thin parts need a smaller edge: more --target-vertices)");
  }
}

}  // namespace vpm
