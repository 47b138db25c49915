#include "vpm/validate.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "mesh/face_table.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace {
[[noreturn]] void fail(const std::string& source, const std::string& where, const std::string& what) {
  throw InputError(source + ": " + where + ": " + what);
}
std::string tet_text(const Tets& t, int i) {
  std::ostringstream s;
  s << "tet " << i << " (" << t(i, 0) << " " << t(i, 1) << " " << t(i, 2) << " " << t(i, 3) << ")";
  return s.str();
}

// Finite coordinates; tet indices in range, no vertex repeated in a tet, no isolated vertex.
void check_indices(const TetMesh& mesh, const std::string& source) {
  const int n = mesh.num_vertices(), m = mesh.num_tets();
  if (n == 0) fail(source, "mesh", "has no vertices");
  if (m == 0) fail(source, "mesh", "has no tets");
  for (int v = 0; v < n; ++v)
    for (int c = 0; c < 3; ++c)
      if (!std::isfinite(mesh.vertices(v, c)))
        fail(source, "vertex " + std::to_string(v), "coordinate " + std::to_string(c) + " is not finite");
  std::vector<char> used(static_cast<size_t>(n), 0);
  for (int t = 0; t < m; ++t) {
    const int* q = &mesh.tets(t, 0);
    const bool in_range = q[0] >= 0 && q[0] < n && q[1] >= 0 && q[1] < n && q[2] >= 0 && q[2] < n &&
                          q[3] >= 0 && q[3] < n;
    const bool distinct = q[0] != q[1] && q[0] != q[2] && q[0] != q[3] && q[1] != q[2] && q[1] != q[3] &&
                          q[2] != q[3];
    if (!in_range || !distinct) {  // the first problem of this tet, in corner order
      for (int c = 0; c < 4; ++c)
        if (q[c] < 0 || q[c] >= n)
          fail(source, "tet " + std::to_string(t),
               "vertex index " + std::to_string(q[c]) + " out of range [0, " + std::to_string(n) + ")");
      fail(source, tet_text(mesh.tets, t), "degenerate: vertex repeated");
    }
    for (int c = 0; c < 4; ++c) used[static_cast<size_t>(q[c])] = 1;
  }
  for (int v = 0; v < n; ++v)
    if (!used[static_cast<size_t>(v)]) fail(source, "vertex " + std::to_string(v), "isolated (in no tet)");
}

// No two tets on the same four vertices: two such tets share each face with the same vertex
// opposite it.
void check_duplicates(const detail::FaceTable& ft, const Tets& tets, const std::string& source) {
  ft.for_each_group([&](int first, int count) {
    for (int i = first; i < first + count; ++i)
      for (int j = i + 1; j < first + count; ++j) {
        const int a = ft.entries[static_cast<size_t>(i)].slot, b = ft.entries[static_cast<size_t>(j)].slot;
        if (tets(a / 4, a % 4) == tets(b / 4, b % 4))
          fail(source, tet_text(tets, std::max(a, b) / 4), "duplicate of tet " + std::to_string(std::min(a, b) / 4));
      }
  });
}

// Rejects zero-volume tets and makes every tet positively oriented (swapping its last two
// vertices), counting and noting the swaps in `rep`.
void check_volumes_and_orient(TetMesh& mesh, const std::string& source, const ValidateOptions& opt,
                              ValidationReport& rep) {
  const int m = mesh.num_tets();
  Eigen::VectorXd vol = tet_volumes(mesh.vertices, mesh.tets);
  const double mean_abs = vol.cwiseAbs().mean();
  for (int t = 0; t < m; ++t)
    if (std::fabs(vol(t)) <= opt.degenerate_relative_volume * mean_abs)
      fail(source, tet_text(mesh.tets, t), "degenerate: zero volume (flat or collinear vertices)");
  for (int t = 0; t < m; ++t)
    if (vol(t) < 0) {
      std::swap(mesh.tets(t, 2), mesh.tets(t, 3));
      ++rep.reoriented_tets;
    }
  if (rep.reoriented_tets)
    rep.notes.push_back("reoriented " + std::to_string(rep.reoriented_tets) +
                        " negatively oriented tets (swapped their last two vertices)");
}

// Manifold tet complex, one connected component.
void check_manifold(const detail::FaceTable& ft, const TetMesh& mesh, const std::string& source) {
  if (int bad = detail::nonmanifold_faces(ft))
    fail(source, "mesh", std::to_string(bad) + " triangles are shared by more than two tets (non-manifold)");
  int comps = 0;
  vertex_components(mesh.num_vertices(), mesh.tets, &comps);
  if (comps != 1) fail(source, "mesh", "has " + std::to_string(comps) + " connected components, expected 1");
}

// Manifold boundary surface (and, if asked, one genus-0 surface); its counts go to `rep`.
void check_boundary(const detail::FaceTable& ft, const TetMesh& mesh, const std::string& source,
                    const ValidateOptions& opt, ValidationReport& rep) {
  const Triangles bf = detail::boundary_faces(ft, mesh.tets);
  const SurfaceTopology st = surface_topology(mesh.num_vertices(), bf);
  rep.boundary_faces = st.faces;
  rep.boundary_vertices = st.vertices;
  rep.boundary_euler = st.euler;
  if (st.nonmanifold_edges || st.open_edges)
    fail(source, "boundary edge (" + std::to_string(st.first_bad_edge[0]) + ", " +
                     std::to_string(st.first_bad_edge[1]) + ")",
         "non-manifold boundary (" + std::to_string(st.nonmanifold_edges + st.open_edges) + " such edges)");
  if (st.nonmanifold_vertices)
    fail(source, "boundary vertex " + std::to_string(st.first_bad_vertex),
         "non-manifold boundary: the surface pinches there (" + std::to_string(st.nonmanifold_vertices) +
             " such vertices)");
  if (opt.require_ball_topology) {
    if (st.components != 1)
      fail(source, "boundary", "has " + std::to_string(st.components) +
                                   " closed surfaces (a cavity?); the ball map needs exactly one");
    if (st.euler != 2)
      fail(source, "boundary", "Euler characteristic " + std::to_string(st.euler) + " (genus " +
                                   std::to_string(st.genus()) + "); the ball map needs a genus-0 surface (2)");
  }
}

// The smallest dihedral angle and its tet.
void measure_quality(const TetMesh& mesh, ValidationReport& rep) {
  const Eigen::VectorXd dih = min_dihedral_angles_deg(mesh.vertices, mesh.tets);
  Eigen::Index r = 0;
  rep.min_dihedral_deg = dih.minCoeff(&r);
  rep.min_dihedral_tet = static_cast<int>(r);
  rep.sliver_tets = static_cast<int>((dih.array() < kSliverDihedralDeg).count());
}

}  // namespace

ValidationReport validate_mesh(TetMesh& mesh, const std::string& source, const ValidateOptions& opt) {
  ValidationReport rep;
  check_indices(mesh, source);
  check_volumes_and_orient(mesh, source, opt, rep);
  const detail::FaceTable ft = detail::face_table(mesh.tets);  // of the oriented tets
  check_duplicates(ft, mesh.tets, source);
  check_manifold(ft, mesh, source);
  check_boundary(ft, mesh, source, opt, rep);
  measure_quality(mesh, rep);
  return rep;
}

}  // namespace vpm
